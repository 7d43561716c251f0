//! Subdivision levels off the render thread (paper 002): the topology phase once per cage and
//! level (a [`Refiner`]: the stencil tables), then the apply phase for the cage and for every
//! frame of `--frames` from the same tables (§6.2.4: one topology refined for every frame),
//! on the GPU when the window's adapter is one and on the CPU otherwise.
//!
//! One worker thread owns the stencil device and the tables uploaded to it, so that a frame
//! costs one apply, not a device and an upload.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Instant;
use tessd_mesh::Mesh;
use tessd_subdiv::{Refiner, Scheme, SubdivOptions};

use super::done::Done;

/// Where the apply phase runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Device {
    /// The CPU (stencil rows in order, [`Refiner::apply`]).
    Cpu,
    /// The GPU compute pass of `tessd-gpu` (its own device on the best adapter).
    Gpu,
}

impl Device {
    /// `CPU` or `GPU`.
    pub fn name(self) -> &'static str {
        match self {
            Device::Cpu => "CPU",
            Device::Gpu => "GPU",
        }
    }
}

/// A request: refine item `item`'s `cage` to `level`, with `positions` (a frame's, or the
/// cage's).
pub struct Job {
    /// The item.
    pub item: usize,
    /// The level (1 or more).
    pub level: u32,
    /// The cage (topology and attributes).
    pub cage: Arc<Mesh>,
    /// The positions to refine (the cage's, or a frame's with as many vertices).
    pub positions: Vec<[f32; 3]>,
    /// Which frame of `--frames` these are (none: the cage's).
    pub frame: Option<usize>,
}

/// The scheme for a cage: Catmull–Clark when it has a face that is not a triangle, else Loop.
pub fn scheme_for(cage: &Mesh) -> Scheme {
    if (0..cage.face_count()).all(|f| cage.face(f).len() == 3) {
        Scheme::Loop
    } else {
        Scheme::CatmullClark
    }
}

/// Starts the worker; it answers on `done`, and ends (dropping its device) when the returned
/// sender is dropped: join the handle then, before the process exits, as a device torn down by
/// the exit itself can crash the driver (lavapipe did).
pub fn start(device: Device, done: Sender<Done>) -> (Sender<Job>, std::thread::JoinHandle<()>) {
    let (tx, rx) = channel::<Job>();
    let handle = std::thread::spawn(move || work(device, &rx, &done));
    (tx, handle)
}

/// The refiner of one item and level, with its tables on the GPU when there is one.
struct Topology {
    item: usize,
    level: u32,
    refiner: Refiner,
    gpu: Option<tessd_gpu::GpuTables>,
}

fn work(device: Device, jobs: &Receiver<Job>, done: &Sender<Done>) {
    let (mut topologies, mut gpu, mut device) = (Vec::new(), None, device);
    let mut state = State {
        topologies: &mut topologies,
        gpu: &mut gpu,
        device: &mut device,
    };
    while let Ok(first) = jobs.recv() {
        // only the newest request of each item is refined; the others are answered skipped
        let mut newest: Vec<Job> = Vec::new();
        for job in std::iter::once(first).chain(jobs.try_iter()) {
            if let Some(i) = newest.iter().position(|n| n.item == job.item) {
                newest.remove(i);
                if done.send(Done::Skipped).is_err() {
                    return;
                }
            }
            newest.push(job);
        }
        for job in newest {
            if done.send(run(&mut state, job)).is_err() {
                return;
            }
        }
    }
}

/// The worker's state: the refiners it built (one per item, the last level asked for), the
/// stencil device, and where it applies.
struct State<'a> {
    topologies: &'a mut Vec<Topology>,
    gpu: &'a mut Option<tessd_gpu::GpuStencils>,
    device: &'a mut Device,
}

fn run(state: &mut State<'_>, job: Job) -> Done {
    let t = Instant::now();
    let scheme = scheme_for(&job.cage);
    let options = SubdivOptions {
        scheme,
        levels: job.level,
        memory_limit: 2 << 30,
        ..SubdivOptions::default()
    };
    let mut built = false;
    let index = match state
        .topologies
        .iter()
        .position(|tp| tp.item == job.item && tp.level == job.level)
    {
        Some(i) => i,
        None => {
            let refiner = match Refiner::new(&job.cage, &options) {
                Ok(r) => r,
                Err(e) => return Done::Failed(format!("subdivision level {}: {e}", job.level)),
            };
            built = true;
            state.topologies.retain(|tp| tp.item != job.item);
            state.topologies.push(Topology {
                item: job.item,
                level: job.level,
                refiner,
                gpu: None,
            });
            state.topologies.len() - 1
        }
    };
    if *state.device == Device::Gpu && state.gpu.is_none() {
        match tessd_gpu::GpuStencils::new() {
            Ok(g) => *state.gpu = Some(g),
            Err(_) => *state.device = Device::Cpu,
        }
    }
    let topology = &mut state.topologies[index];
    let flat = job.positions.as_flattened();
    let positions = match (*state.device, state.gpu.as_ref()) {
        (Device::Gpu, Some(g)) => {
            if topology.gpu.is_none() {
                match g.upload(&topology.refiner.tables) {
                    Ok(t) => topology.gpu = Some(t),
                    Err(e) => return Done::Failed(format!("GPU subdivision: {e}")),
                }
            }
            let tables = topology.gpu.as_ref().expect("uploaded above");
            g.apply(tables, flat, 3).map_err(|e| e.to_string())
        }
        _ => topology
            .refiner
            .apply(flat, 3, "the cage")
            .map_err(|e| e.to_string()),
    };
    let positions: Vec<[f32; 3]> = match positions {
        Ok(p) => p.as_chunks::<3>().0.to_vec(),
        Err(e) => return Done::Failed(format!("subdivision level {}: {e}", job.level)),
    };
    // shading normals follow the rest pose only, as `tessd subdivide` does with frames
    let mesh_options = SubdivOptions {
        normals: job.frame.is_none(),
        ..options
    };
    match topology
        .refiner
        .mesh_with(&job.cage, positions, &mesh_options)
    {
        Ok(mesh) => Done::Subdivided {
            item: job.item,
            level: job.level,
            mesh: Box::new(mesh),
            scheme: scheme.name(),
            device: state.device.name(),
            topology_built: built,
            frame: job.frame,
            ms: t.elapsed().as_secs_f64() * 1e3,
        },
        Err(e) => Done::Failed(format!("subdivision level {}: {e}", job.level)),
    }
}
