//! Work off the render thread (issue 35: the window stays responsive): LOD chains on one-shot
//! threads, subdivision on its worker ([`super::subdivision`]), and a `.tsc` file's refinement
//! on a worker that keeps its view session (paper 003 §6.2) and always refines for the newest
//! camera it was sent, skipping the ones that went by while it was busy.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Instant;
use tessd_codec::{Tsc, ViewSession};
use tessd_mesh::Mesh;
use tessd_simplify::{Method, SimplifyOptions};

pub use super::done::Done;
use super::subdivision::{self, Device, Job};
use crate::ops::codec::to_mesh;

/// The channel background work answers on, and how much of it is still running.
pub struct Background {
    tx: Sender<Done>,
    rx: Receiver<Done>,
    /// Jobs sent and not answered yet.
    pub busy: usize,
    /// The subdivision worker, started on first use.
    subdivider: Option<(Sender<Job>, std::thread::JoinHandle<()>)>,
    /// Where it applies stencils.
    pub device: Device,
}

impl Background {
    /// No work yet; subdivision will apply on `device`.
    pub fn new(device: Device) -> Self {
        let (tx, rx) = channel();
        Background {
            tx,
            rx,
            busy: 0,
            subdivider: None,
            device,
        }
    }

    /// Sends a subdivision request to the worker.
    pub fn subdivide(&mut self, job: Job) {
        let (worker, _) = self
            .subdivider
            .get_or_insert_with(|| subdivision::start(self.device, self.tx.clone()));
        if worker.send(job).is_ok() {
            self.busy += 1;
        }
    }
}

impl Background {
    /// Runs `job` on its own thread.
    pub fn spawn(&mut self, job: impl FnOnce() -> Done + Send + 'static) {
        let tx = self.tx.clone();
        self.busy += 1;
        std::thread::spawn(move || {
            let _ = tx.send(job());
        });
    }

    /// What finished since the last call.
    pub fn poll(&mut self) -> Vec<Done> {
        let done: Vec<Done> = self.rx.try_iter().collect();
        self.busy -= done.len().min(self.busy);
        done
    }

    /// A refiner for item `item` answering on this channel.
    pub fn refiner(&self, item: usize, tsc: Arc<Tsc>, pixel_error: f64) -> Refinement {
        let (cams, rx) = channel::<tessd_codec::Camera>();
        let tx = self.tx.clone();
        let sessions = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let counter = sessions.clone();
        std::thread::spawn(move || {
            let mut session = ViewSession::new(tsc);
            counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            while let Ok(mut camera) = rx.recv() {
                // only the newest camera matters
                while let Ok(newer) = rx.try_recv() {
                    camera = newer;
                }
                let t = Instant::now();
                let done = match session.view(&camera, pixel_error) {
                    Ok(view) => Done::Refined {
                        item,
                        scene: Box::new(tessd_render::Scene::from_mesh(&to_mesh(
                            &view.positions,
                            &view.triangles,
                        ))),
                        cells: view.cells.len(),
                        triangles: view.triangles.len(),
                        bytes_read: view.bytes_read,
                        ms: t.elapsed().as_secs_f64() * 1e3,
                    },
                    Err(e) => Done::Failed(e.to_string()),
                };
                if tx.send(done).is_err() {
                    return;
                }
            }
        });
        Refinement {
            cams,
            in_flight: 0,
            last: None,
            views: 0,
            bytes_read: 0,
            cells: 0,
            sessions,
        }
    }
}

impl Drop for Background {
    /// Stops the subdivision worker and waits for it to drop its device.
    fn drop(&mut self) {
        if let Some((jobs, handle)) = self.subdivider.take() {
            drop(jobs);
            let _ = handle.join();
        }
    }
}

/// The render thread's side of a `.tsc` item's worker.
pub struct Refinement {
    cams: Sender<tessd_codec::Camera>,
    /// Cameras sent and not answered (the worker answers the newest of a burst only, so this
    /// counts bursts).
    pub in_flight: usize,
    /// The last camera sent (a camera that did not move is not sent again).
    pub last: Option<tessd_codec::Camera>,
    /// Views answered by the one session (a moving camera refines the session it has).
    pub views: u64,
    /// Bytes of code read, over all views.
    pub bytes_read: u64,
    /// Cells shown by the last view.
    pub cells: usize,
    /// View sessions the worker opened (one for its life: every camera refines the same one).
    pub sessions: Arc<std::sync::atomic::AtomicU64>,
}

impl Refinement {
    /// Asks for `camera` unless it is the last one asked for.
    pub fn request(&mut self, camera: tessd_codec::Camera) {
        if self.last.as_ref() == Some(&camera) {
            return;
        }
        self.last = Some(camera);
        if self.cams.send(camera).is_ok() {
            self.in_flight = 1;
        }
    }
}

/// The LOD chain of `mesh`: the complexity goal (paper 004 §4) at 1/2, 1/4, 1/8 and 1/16 of its
/// vertices, each with its partition's cells (`P` shows them).
pub fn lod_chain(item: usize, mesh: Arc<Mesh>) -> Done {
    let t = Instant::now();
    let methods: Vec<Method> = [0.5, 0.25, 0.125, 0.0625]
        .iter()
        .map(|&f| Method::Complexity(tessd_simplify::Count::Relative(f)))
        .collect();
    let mut options = SimplifyOptions::new(methods[0]);
    options.keep_partition = true;
    match tessd_simplify::lod::lod_chain(&mesh, &methods, &options, &mut |_, _| true) {
        Ok(chain) => Done::Lods {
            item,
            levels: chain.into_iter().map(|s| (s.mesh, s.cells)).collect(),
            ms: t.elapsed().as_secs_f64() * 1e3,
        },
        Err(e) => Done::Failed(format!("LOD chain: {e}")),
    }
}
