//! The window and its event loop (winit): input to camera moves and key commands, one frame
//! per redraw (every item rendered on the window's device and composited by depth), the
//! heads-up text, and the script's actions between frames.

use anyhow::{Context, Result, anyhow};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use tessd_mesh::Mesh;
use tessd_render::present::Presenter;
use tessd_render::{Bounds, Cracks, DrawMode, Frame, RenderSettings, Renderer, Shading, View};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

use super::background::{Background, Done, Refinement, lod_chain};
use super::hud::{Canvas, HELP};
use super::items::{self, Item, MeshItem, Prepared};
use super::navigation::{Navigation, ORBIT_PER_PIXEL};
use super::script::Action;
use super::stats::FrameStats;
use super::subdivision::{Device, Job};
use super::{MAX_LEVEL, Options};

/// Opens the window and runs until it closes.
///
/// # Errors
/// No display or adapter, a device failure, or a script action that fails.
pub fn run(
    options: Options,
    prepared: Vec<Prepared>,
    frames: Vec<Mesh>,
    script: Vec<Action>,
) -> Result<()> {
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!(
            "tessd view cannot reach the display (DISPLAY={:?}, WAYLAND_DISPLAY={:?}): {e}",
            std::env::var("DISPLAY").unwrap_or_default(),
            std::env::var("WAYLAND_DISPLAY").unwrap_or_default()
        )
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        options,
        prepared: Some(prepared),
        frames,
        script,
        state: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The event handler: the options until the window exists, then its state.
struct App {
    options: Options,
    prepared: Option<Vec<Prepared>>,
    frames: Vec<Mesh>,
    script: Vec<Action>,
    state: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        let prepared = self.prepared.take().unwrap_or_default();
        let script = std::mem::take(&mut self.script);
        let frames = std::mem::take(&mut self.frames);
        match Viewer::open(event_loop, &self.options, prepared, frames, script) {
            Ok(v) => self.state = Some(v),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(v) = self.state.as_mut() else {
            return;
        };
        if let Err(e) = v.event(event_loop, event) {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    /// Draws again while anything moves (input, background work, a script, playing frames);
    /// a still scene waits for events instead of spinning.
    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(v) = &mut self.state {
            if v.needs_frame() {
                v.window.request_redraw();
                event_loop.set_control_flow(ControlFlow::Poll);
            } else {
                event_loop.set_control_flow(ControlFlow::Wait);
            }
        }
    }
}

/// A `.tsc` item's refinement state.
struct TscItem {
    item: usize,
    refinement: Refinement,
}

/// The window's state.
struct Viewer {
    window: Arc<Window>,
    renderer: Renderer,
    presenter: Presenter,
    items: Vec<Item>,
    tsc: Vec<TscItem>,
    background: Background,
    nav: Navigation,
    settings: RenderSettings,
    cracks: Cracks,
    /// Subdivision level asked for, and the level shown.
    level: u32,
    shown_level: u32,
    subdiv_scheme: &'static str,
    subdiv_device: &'static str,
    /// Topology phases run (a frame of `--frames` reuses its level's).
    topologies: u64,
    /// LOD shown (0: the input), and whether the partition is shown.
    lod: usize,
    show_partition: bool,
    frames: Vec<Mesh>,
    frame_index: usize,
    playing: bool,
    help: bool,
    script: Vec<Action>,
    next_action: usize,
    wait: u32,
    until_idle: bool,
    /// Frame-time statistics.
    stats: FrameStats,
    last_start: Option<Instant>,
    /// Mouse: buttons held, last position, modifiers.
    orbiting: bool,
    panning: bool,
    cursor: Option<(f64, f64)>,
    modifiers: ModifiersState,
    screenshots: u32,
    /// An event since the last frame may have changed the picture.
    dirty: bool,
    /// The LOD step asked for while the chain was being built.
    lod_step_pending: isize,
    last_frame: Option<Frame>,
    messages: Vec<String>,
}

impl Viewer {
    fn open(
        event_loop: &ActiveEventLoop,
        options: &Options,
        prepared: Vec<Prepared>,
        frames: Vec<Mesh>,
        script: Vec<Action>,
    ) -> Result<Viewer> {
        let (w, h) = options.size;
        let title = format!(
            "tessd view - {}",
            options
                .inputs
                .iter()
                .map(|p| p
                    .file_name()
                    .map_or_else(String::new, |n| n.to_string_lossy().into()))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let attributes = Window::default_attributes()
            .with_title(title)
            .with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let (gpu, surface, formats) =
            tessd_gpu::GpuContext::open_for_window("tessd-view", window.clone())?;
        let renderer = Renderer::with_context(gpu)?;
        let size = window.inner_size();
        let presenter = Presenter::new(
            renderer.context(),
            surface,
            &formats,
            size.width.max(1),
            size.height.max(1),
        )?;
        let device = match options.subdivision_device {
            Some(d) => d,
            None if renderer.adapter().device_type == "Cpu" => Device::Cpu,
            None => Device::Gpu,
        };
        let background = Background::new(device);
        let mut items = Vec::new();
        let mut tsc = Vec::new();
        let mut bounds: Option<Bounds> = None;
        for p in prepared {
            match p {
                Prepared::Tsc(path, file) => {
                    let b = tsc_bounds(&file);
                    bounds = Some(bounds.map_or(b, |a| a.union(&b)));
                    let item = items.len();
                    items.push(Item::Mesh(Box::new(MeshItem::new(path, Mesh::default()))));
                    tsc.push(TscItem {
                        item,
                        refinement: background.refiner(item, file, options.pixel_error),
                    });
                }
                other => {
                    let item = items::upload(other, &renderer)?;
                    if let Some(b) = item.bounds() {
                        bounds = Some(bounds.map_or(b, |a| a.union(&b)));
                    }
                    items.push(item);
                }
            }
        }
        let bounds = bounds.context("nothing to draw: the inputs are empty")?;
        let aspect = size.width.max(1) as f64 / size.height.max(1) as f64;
        let mut nav =
            Navigation::fitted(options.view, options.up_axis, bounds, options.fov, aspect);
        if let Some((eye, target, up)) = options.eye {
            let target = target.map_or(bounds.center(), glam::DVec3::from);
            let up = up.map_or(options.up_axis.vector(), glam::DVec3::from);
            nav.set_camera(eye.into(), target, up, options.fov);
        }
        let settings = RenderSettings::new(size.width.max(1), size.height.max(1))
            .with_shading(options.shading)
            .with_edges(options.edges)
            .with_mode(options.mode);
        println!("view: adapter {}", renderer.adapter_info());
        let mut v = Viewer {
            window,
            renderer,
            presenter,
            items,
            tsc,
            background,
            nav,
            settings,
            cracks: options.cracks,
            level: 0,
            shown_level: 0,
            subdiv_scheme: "",
            subdiv_device: "",
            topologies: 0,
            lod: 0,
            show_partition: false,
            frames,
            frame_index: 0,
            playing: false,
            help: false,
            script,
            next_action: 0,
            wait: 0,
            until_idle: false,
            stats: FrameStats::default(),
            last_start: None,
            orbiting: false,
            panning: false,
            cursor: None,
            modifiers: ModifiersState::empty(),
            screenshots: 0,
            lod_step_pending: 0,
            dirty: true,
            last_frame: None,
            messages: Vec::new(),
        };
        if options.subdivide > 0 {
            v.set_level(options.subdivide.min(MAX_LEVEL));
        }
        Ok(v)
    }

    /// One window event.
    /// Whether the next frame can differ from the last one.
    fn needs_frame(&mut self) -> bool {
        let dirty = std::mem::take(&mut self.dirty);
        dirty
            || self.next_action < self.script.len()
            || self.wait > 0
            || self.until_idle
            || self.playing
            || self.busy()
            || self.last_frame.is_none()
    }

    fn event(&mut self, event_loop: &ActiveEventLoop, event: WindowEvent) -> Result<()> {
        // anything but a redraw may change the picture
        self.dirty |= !matches!(event, WindowEvent::RedrawRequested);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                self.presenter
                    .resize(self.renderer.context(), size.width, size.height);
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                if let Some(name) = key_name(&event.logical_key) {
                    if name == "escape" {
                        event_loop.exit();
                    } else {
                        self.press(&name)?;
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Middle if self.modifiers.shift_key() => self.panning = down,
                    MouseButton::Middle | MouseButton::Left => self.orbiting = down,
                    _ => {}
                }
                if !down {
                    self.panning = false;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let Some((x, y)) = self.cursor {
                    let (dx, dy) = (now.0 - x, now.1 - y);
                    if self.panning {
                        self.nav.pan(dx, dy, self.settings.height);
                    } else if self.orbiting {
                        self.nav.orbit(dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL);
                    }
                }
                self.cursor = Some(now);
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                self.nav.zoom(0.85f64.powf(steps));
            }
            WindowEvent::RedrawRequested if !self.frame(event_loop)? => event_loop.exit(),
            _ => {}
        }
        Ok(())
    }

    fn aspect(&self) -> f64 {
        self.settings.aspect()
    }

    /// Says a change of state on stdout (tests and users read what a key did).
    fn say(&mut self, line: String) {
        println!("view: {line}");
        self.messages.push(line);
        if self.messages.len() > 3 {
            self.messages.remove(0);
        }
    }

    /// A key command, by the help overlay's names.
    fn press(&mut self, name: &str) -> Result<()> {
        match name {
            "1" => self.nav.view(View::Front, self.aspect()),
            "3" => self.nav.view(View::Right, self.aspect()),
            "7" => self.nav.view(View::Top, self.aspect()),
            "9" => self.nav.opposite(),
            "5" => {
                self.nav.toggle_ortho();
                let look = if self.nav.ortho {
                    "orthographic"
                } else {
                    "perspective"
                };
                self.say(format!("camera {look}"));
            }
            "home" => self.nav.frame_all(self.aspect()),
            "w" => {
                let i = DrawMode::ALL.iter().position(|&m| m == self.settings.mode);
                let next = DrawMode::ALL[(i.unwrap_or(0) + 1) % DrawMode::ALL.len()];
                self.settings.mode = next;
                self.say(format!("mode {}", next.name()));
            }
            "e" => {
                self.settings.edges = !self.settings.edges;
                self.say(format!(
                    "edges {}",
                    if self.settings.edges { "on" } else { "off" }
                ));
            }
            "f" => {
                self.settings.shading = if self.settings.shading == Shading::FaceIds {
                    Shading::Lit
                } else {
                    Shading::FaceIds
                };
                self.say(format!("shading {}", self.settings.shading.name()));
            }
            "c" => {
                self.cracks = match self.cracks {
                    Cracks::None => Cracks::Image,
                    Cracks::Image => Cracks::Object,
                    Cracks::Object => Cracks::None,
                };
                self.say(format!("cracks {}", self.cracks.name()));
            }
            "h" => self.help = !self.help,
            "plus" => self.set_level((self.level + 1).min(MAX_LEVEL)),
            "minus" => self.set_level(self.level.saturating_sub(1)),
            "space" => {
                if self.frames.is_empty() {
                    self.say("no --frames to play".into());
                } else {
                    self.playing = !self.playing;
                    self.say(format!(
                        "frames {}",
                        if self.playing { "playing" } else { "paused" }
                    ));
                }
            }
            "f12" => {
                let path = self.screenshot_path();
                self.screenshot(&path, None)?;
            }
            "bracketleft" | "bracketright" => {
                let step: isize = if name == "bracketright" { 1 } else { -1 };
                self.step_lod(step)?;
            }
            "p" => {
                self.show_partition = !self.show_partition;
                self.show_lod()?;
            }
            other => self.say(format!("no command on key `{other}` (H lists the keys)")),
        }
        Ok(())
    }

    /// Asks for subdivision level `level` of every mesh item (the cage at 0), computed in the
    /// background, of the frame of `--frames` shown (if any).
    fn set_level(&mut self, level: u32) {
        self.level = level;
        for i in 0..self.items.len() {
            let Item::Mesh(m) = &mut self.items[i] else {
                continue;
            };
            if self.tsc.iter().any(|t| t.item == i) {
                continue;
            }
            let frame = self
                .frames
                .get(self.frame_index)
                .filter(|_| self.playing || self.frame_index > 0);
            if level == 0 {
                let mesh = match frame {
                    Some(f) => with_positions(&m.cage, f),
                    None => (*m.cage).clone(),
                };
                let _ = m.show(&mesh, &self.renderer);
                self.shown_level = 0;
                continue;
            }
            let positions = match frame {
                Some(f) if f.positions.len() == m.cage.positions.len() => f.positions.clone(),
                _ => m.cage.positions.clone(),
            };
            let job = Job {
                item: i,
                level,
                cage: m.cage.clone(),
                positions,
                frame: frame.map(|_| self.frame_index),
            };
            self.background.subdivide(job);
        }
        if level == 0 {
            self.say(format!(
                "subdivision 0 (cage): {} triangles",
                self.triangles()
            ));
        }
    }

    /// Steps the LOD shown by `step` (the chain is built in the background on first use).
    fn step_lod(&mut self, step: isize) -> Result<()> {
        let mut building = false;
        for (i, item) in self.items.iter().enumerate() {
            if let Item::Mesh(m) = item
                && m.lods.is_none()
                && !self.tsc.iter().any(|t| t.item == i)
            {
                let cage = m.cage.clone();
                self.background.spawn(move || lod_chain(i, cage));
                building = true;
            }
        }
        if building {
            self.say("building the LOD chain in the background".into());
            self.lod_step_pending = step;
            return Ok(());
        }
        let max = self
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Mesh(m) => m.lods.as_ref().map(Vec::len),
                _ => None,
            })
            .max()
            .unwrap_or(0);
        self.lod = (self.lod as isize + step).clamp(0, max as isize) as usize;
        self.show_lod()
    }

    /// Shows LOD `self.lod` of every mesh item (0: the input, at the subdivision level asked
    /// for), with its partition when `P` is on.
    fn show_lod(&mut self) -> Result<()> {
        let (lod, partition) = (self.lod, self.show_partition);
        for item in &mut self.items {
            let Item::Mesh(m) = item else { continue };
            let Some(lods) = m.lods.take() else { continue };
            let result = (|| -> Result<()> {
                if lod == 0 {
                    let cage = m.cage.clone();
                    m.show(&cage, &self.renderer)?;
                    // the input's partition is the first level's
                    let cells = lods.first().map(|l| l.1.as_slice()).filter(|_| partition);
                    m.show_partition(cells, &self.renderer)?;
                } else if let Some((mesh, cells)) = lods.get(lod - 1) {
                    m.show(mesh, &self.renderer)?;
                    m.show_partition(Some(cells.as_slice()).filter(|_| partition), &self.renderer)?;
                }
                Ok(())
            })();
            m.lods = Some(lods);
            result?;
        }
        self.shown_level = 0;
        let t = self.triangles();
        self.say(format!(
            "LOD {lod}{}: {t} triangles",
            if partition { " with its partition" } else { "" }
        ));
        Ok(())
    }

    fn triangles(&self) -> u64 {
        self.items.iter().map(Item::triangles).sum()
    }

    /// Where F12 saves: `<first input's stem>_view_NNN.png` beside it.
    fn screenshot_path(&mut self) -> PathBuf {
        self.screenshots += 1;
        let first = self.items[0].path();
        let stem = first
            .file_stem()
            .map_or_else(|| "view".into(), |s| s.to_string_lossy().into_owned());
        first.with_file_name(format!("{stem}_view_{:03}.png", self.screenshots))
    }

    /// Writes the last frame's colour (and face ids) as `tessd render` does.
    fn screenshot(&mut self, color: &Path, face_ids: Option<&Path>) -> Result<()> {
        let frame = self.last_frame.as_ref().context("no frame drawn yet")?;
        tessd_render::image::write_png(color, frame.width, frame.height, &frame.color)?;
        if let Some(p) = face_ids {
            let ids = tessd_render::image::face_ids_to_rgba(&frame.face_id);
            tessd_render::image::write_png(p, frame.width, frame.height, &ids)?;
        }
        self.say(format!("screenshot {}", color.display()));
        Ok(())
    }

    /// The state a `stats` action writes.
    fn stats_json(&self) -> Value {
        let breps: Vec<_> = self
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Brep(b) => Some(b.report),
                _ => None,
            })
            .collect();
        let (bytes, cells, views, in_flight): (u64, usize, u64, usize) =
            self.tsc.iter().fold((0, 0, 0, 0), |a, t| {
                let r = &t.refinement;
                (
                    a.0 + r.bytes_read,
                    a.1 + r.cells,
                    a.2 + r.views,
                    a.3 + r.in_flight,
                )
            });
        let c = &self.nav.camera;
        self.stats.to_json(json!({
            "triangles": self.triangles(),
            "mode": self.settings.mode.name(),
            "shading": self.settings.shading.name(),
            "edges": self.settings.edges,
            "cracks": self.cracks.name(),
            "subdivision_level": self.shown_level,
            "subdivision_scheme": self.subdiv_scheme,
            "subdivision_device": self.subdiv_device,
            "subdivision_topologies": self.topologies,
            "lod": self.lod,
            "partition": self.show_partition,
            "triangles_near_target": self.triangles_near_target(),
            "sessions": self.tsc.iter().map(|t| {
                t.refinement.sessions.load(std::sync::atomic::Ordering::Relaxed)
            }).sum::<u64>(),
            "frame_index": self.frame_index,
            "frames_total": self.frames.len(),
            "bytes_read": bytes,
            "cells": cells,
            "views": views,
            "refining": in_flight > 0,
            "background_jobs": self.background.busy,
            "adapter": self.renderer.adapter_info(),
            "size": [self.settings.width, self.settings.height],
            "camera": {"eye": c.eye.to_array(), "target": c.target.to_array(),
                       "up": c.up.to_array(), "fov": c.fov},
            "step_times_ms": (!breps.is_empty())
                .then(|| crate::ops::render::step_timings(&breps)),
        }))
    }

    /// Triangles shown whose centroid lies within 10 % of the scene's radius of the camera's
    /// target (what a view-dependent refinement puts where the camera looks).
    fn triangles_near_target(&self) -> u64 {
        let target = self.nav.camera.target;
        let r = 0.1 * self.nav.bounds.radius();
        let mut n = 0;
        for item in &self.items {
            let Item::Mesh(m) = item else { continue };
            let Some((scene, _)) = &m.shown else { continue };
            let origin = scene.origin;
            for t in scene.vertices.chunks_exact(3) {
                let c = t.iter().fold(glam::DVec3::ZERO, |a, v| {
                    a + glam::DVec3::from(v.position.map(f64::from))
                }) / 3.0
                    + origin;
                n += u64::from(c.distance(target) <= r);
            }
        }
        n
    }

    /// Background work still running (refinements in flight included).
    fn busy(&self) -> bool {
        self.background.busy > 0 || self.tsc.iter().any(|t| t.refinement.in_flight > 0)
    }

    /// Runs the script's actions up to the next one that needs frames. Returns false to quit.
    fn run_script(&mut self, shots: &mut Vec<Shot>) -> Result<bool> {
        if self.wait > 0 {
            self.wait -= 1;
            return Ok(true);
        }
        if self.until_idle {
            if self.busy() {
                return Ok(true);
            }
            self.until_idle = false;
        }
        while let Some(action) = self.script.get(self.next_action).cloned() {
            self.next_action += 1;
            match action {
                Action::Wait(n) => {
                    self.wait = n;
                    return Ok(true);
                }
                Action::Camera {
                    eye,
                    target,
                    up,
                    fov,
                } => {
                    let fov = fov.unwrap_or(self.nav.camera.fov);
                    self.nav
                        .set_camera(eye.into(), target.into(), up.into(), fov);
                }
                Action::Orbit(dx, dy) => self.nav.orbit(dx, dy),
                Action::Zoom(f) => self.nav.zoom(f),
                Action::Key(k) if k == "escape" => return Ok(false),
                Action::Key(k) => self.press(&k)?,
                Action::UntilIdle => {
                    self.until_idle = true;
                    return Ok(true);
                }
                Action::Screenshot {
                    color,
                    face_ids,
                    overlay,
                } => {
                    // taken from the frame drawn next, after the actions before it
                    shots.push(Shot {
                        color,
                        face_ids,
                        overlay,
                    });
                    return Ok(true);
                }
                Action::Stats(path) => {
                    let text = serde_json::to_string_pretty(&self.stats_json())?;
                    tessd_mesh::io::write_atomic(&path, |w| {
                        w.write_all(text.as_bytes())
                            .map_err(|source| tessd_mesh::MeshError::Io {
                                path: path.display().to_string(),
                                source,
                            })
                    })?;
                    self.say(format!("stats {}", path.display()));
                }
                Action::Quit => return Ok(false),
            }
        }
        Ok(true)
    }

    /// Applies what the background work finished.
    fn take_background(&mut self) -> Result<()> {
        for done in self.background.poll() {
            match done {
                Done::Subdivided {
                    item,
                    level,
                    mesh,
                    scheme,
                    device,
                    topology_built,
                    frame,
                    ms,
                } => {
                    self.topologies += u64::from(topology_built);
                    if level != self.level {
                        continue;
                    }
                    if let Some(Item::Mesh(m)) = self.items.get_mut(item) {
                        m.show(&mesh, &self.renderer)?;
                    }
                    self.shown_level = level;
                    self.subdiv_scheme = scheme;
                    self.subdiv_device = device;
                    let t = self.triangles();
                    if frame.is_none() || topology_built {
                        let phase = if topology_built {
                            "topology and apply"
                        } else {
                            "apply"
                        };
                        self.say(format!(
                            "subdivision {level} ({scheme}, {device}, {phase} {ms:.0} ms): {t} triangles"
                        ));
                    }
                }
                Done::Skipped => {}
                Done::Lods { item, levels, ms } => {
                    let n = levels.len();
                    if let Some(Item::Mesh(m)) = self.items.get_mut(item) {
                        m.lods = Some(levels);
                    }
                    self.say(format!("LOD chain built: {n} levels ({ms:.0} ms)"));
                    let step = std::mem::take(&mut self.lod_step_pending);
                    if step != 0 && !self.busy() {
                        self.step_lod(step)?;
                    }
                }
                Done::Refined { item, view, ms } => {
                    let mesh = view_mesh(&view);
                    if let Some(Item::Mesh(m)) = self.items.get_mut(item) {
                        m.show(&mesh, &self.renderer)?;
                    }
                    if let Some(t) = self.tsc.iter_mut().find(|t| t.item == item) {
                        let r = &mut t.refinement;
                        r.in_flight = 0;
                        r.views += 1;
                        r.bytes_read += view.bytes_read;
                        r.cells = view.cells.len();
                    }
                    self.say(format!(
                        "refined: {} cells, {} triangles, {} bytes read ({ms:.0} ms)",
                        view.cells.len(),
                        view.triangles.len(),
                        view.bytes_read
                    ));
                }
                Done::Failed(why) => self.say(format!("failed: {why}")),
            }
        }
        Ok(())
    }

    /// Draws one frame. Returns false to quit.
    fn frame(&mut self, _: &ActiveEventLoop) -> Result<bool> {
        let start = Instant::now();
        if let Some(last) = self.last_start.replace(start) {
            self.stats
                .frame_ms
                .push(start.duration_since(last).as_secs_f64() * 1e3);
            if self.busy() {
                self.stats.frames_while_busy += 1;
            }
        }
        self.take_background()?;
        let mut shots = Vec::new();
        let go_on = self.run_script(&mut shots)?;
        if self.playing && !self.frames.is_empty() {
            self.frame_index = (self.frame_index + 1) % self.frames.len();
            self.show_frame()?;
        }
        let (w, h) = self.presenter.size();
        self.settings.width = w;
        self.settings.height = h;
        self.nav.camera = self.nav.camera.clipped_to(&self.nav.bounds);
        // the .tsc workers refine for the camera as it is now
        for t in &mut self.tsc {
            let c = &self.nav.camera;
            t.refinement.request(tessd_codec::Camera {
                eye: c.eye.to_array(),
                target: c.target.to_array(),
                up: c.up.to_array(),
                fov: c.fov,
                width: w,
                height: h,
            });
        }
        let mut frame = Frame {
            width: w,
            height: h,
            color: [38u8, 38, 42, 255].repeat((w * h) as usize),
            depth: vec![f32::INFINITY; (w * h) as usize],
            face_id: vec![0; (w * h) as usize],
            uv: vec![[0.0; 2]; (w * h) as usize],
        };
        let mut offset = 0u32;
        let mut first = true;
        for item in &mut self.items {
            if let Some(f) = item.render(
                &self.renderer,
                &self.nav.camera,
                &self.settings,
                self.cracks,
            )? {
                if first {
                    frame = f;
                    first = false;
                } else {
                    items::composite(&mut frame, &f, offset);
                }
            }
            offset += item_faces(item);
        }
        let mut shown = frame.color.clone();
        self.last_frame = Some(frame);
        let mut lines = self.hud_lines();
        lines.extend(self.messages.iter().cloned());
        let mut canvas = Canvas {
            rgba: &mut shown,
            width: w as usize,
            height: h as usize,
        };
        canvas.block(0, &lines);
        if self.help {
            let help: Vec<String> = HELP.iter().map(|s| s.to_string()).collect();
            canvas.block(h as usize / 3, &help);
        }
        for shot in shots {
            self.screenshot(&shot.color, shot.face_ids.as_deref())?;
            if shot.overlay {
                tessd_render::image::write_png(&shot.color, w, h, &shown)?;
            }
        }
        self.presenter
            .present(self.renderer.context(), w, h, &shown)?;
        Ok(go_on)
    }

    /// The heads-up lines: what is drawn and how, each B-Rep part's steps, each `.tsc`'s
    /// reading.
    fn hud_lines(&self) -> Vec<String> {
        let last = self.stats.frame_ms.last().copied().unwrap_or(0.0);
        let mut lines = vec![format!(
            "{} tris  {}  {}{}  subdiv {}  LOD {}  {last:.0} ms/frame  (H: keys)",
            self.triangles(),
            self.settings.mode.name(),
            self.settings.shading.name(),
            if self.settings.edges { "+edges" } else { "" },
            self.shown_level,
            self.lod,
        )];
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        for item in &self.items {
            if let Item::Brep(b) = item {
                let t = &b.report.timings;
                lines.push(format!(
                    "B-Rep {} faces, cracks {}: tessellate {:.1}  trim {:.1}  detect {:.1}  fill {:.1} ms",
                    b.faces,
                    self.cracks.name(),
                    ms(t.tessellation),
                    ms(t.initial),
                    ms(t.crack_detection),
                    ms(t.image_fill + t.depth_mask + t.object_fill + t.composite),
                ));
            }
        }
        for t in &self.tsc {
            let r = &t.refinement;
            lines.push(format!(
                "tsc: {} bytes read, {} cells, {} triangles shown{}",
                r.bytes_read,
                r.cells,
                self.items[t.item].triangles(),
                if r.in_flight > 0 { ", refining" } else { "" }
            ));
        }
        lines
    }

    /// Shows frame `frame_index` of `--frames` at the subdivision level asked for (its
    /// topology refined once, reused for every frame).
    fn show_frame(&mut self) -> Result<()> {
        self.set_level(self.level);
        Ok(())
    }
}

/// A screenshot a script asked for.
struct Shot {
    color: PathBuf,
    face_ids: Option<PathBuf>,
    overlay: bool,
}

/// Faces an item's ids run over (the next item's ids start after them).
fn item_faces(item: &Item) -> u32 {
    match item {
        Item::Mesh(m) => m.shown.as_ref().map_or(0, |(s, _)| {
            s.vertices.iter().map(|v| v.face_id).max().unwrap_or(0)
        }),
        Item::Brep(b) => b.faces as u32,
    }
}

/// `cage` with the positions of `frame` (same vertex count).
fn with_positions(cage: &Mesh, frame: &Mesh) -> Mesh {
    let mut m = cage.clone();
    if frame.positions.len() == m.positions.len() {
        m.positions.clone_from(&frame.positions);
    }
    m
}

/// A view-dependent decode as a mesh.
fn view_mesh(view: &tessd_codec::ViewMesh) -> Mesh {
    let mut mesh = Mesh {
        positions: view.positions.iter().map(|p| p.map(|x| x as f32)).collect(),
        ..Mesh::default()
    };
    for t in &view.triangles {
        mesh.push_face(t);
    }
    mesh
}

/// The box of a `.tsc` file's quantisation grid.
fn tsc_bounds(tsc: &tessd_codec::Tsc) -> Bounds {
    let grid = &tsc.header.grid;
    let n = (1u64 << tsc.header.params.bits) as f64;
    Bounds {
        min: grid.position([-0.5; 3]).into(),
        max: grid.position([n - 0.5; 3]).into(),
    }
}

/// A key's name in the help overlay and in scripts: letters lower case, `plus`, `minus`,
/// `bracketleft`, `bracketright`, `space`, `home`, `f12`, `escape`, digits (numpad or not).
pub fn key_name(key: &Key) -> Option<String> {
    Some(match key {
        Key::Named(NamedKey::Escape) => "escape".into(),
        Key::Named(NamedKey::Home) => "home".into(),
        Key::Named(NamedKey::F12) => "f12".into(),
        Key::Named(NamedKey::Space) => "space".into(),
        Key::Character(s) => match s.as_str() {
            "+" | "=" => "plus".into(),
            "-" | "_" => "minus".into(),
            "[" => "bracketleft".into(),
            "]" => "bracketright".into(),
            " " => "space".into(),
            other => other.to_lowercase(),
        },
        _ => return None,
    })
}
