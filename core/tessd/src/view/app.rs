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

mod commands;
mod frame;
mod scripted;

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

    /// One window event.
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

    fn triangles(&self) -> u64 {
        self.items.iter().map(Item::triangles).sum()
    }

    /// Background work still running (refinements in flight included).
    fn busy(&self) -> bool {
        self.background.busy > 0 || self.tsc.iter().any(|t| t.refinement.in_flight > 0)
    }
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
