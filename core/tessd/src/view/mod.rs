//! `tessd view`: the papers' interactive applications in a window (issue 35). Meshes, B-Rep
//! parts and compressed meshes in one scene, drawn by `tessd render`'s renderer on the
//! window's device every frame, moved with Blender's keys and mouse, or by a script.
//!
//! One module per concern: [`items`] (the inputs and their device buffers), [`navigation`]
//! (the camera), [`background`] (subdivision and `.tsc` refinement off the render thread),
//! [`script`] (`--script` actions), [`stats`] (what a scripted run reports), [`hud`] (the
//! heads-up line and the help overlay), [`app`] (the window and its event loop).

pub mod app;
pub mod background;
pub mod done;
pub mod hud;
pub mod items;
pub mod navigation;
pub mod partition_colors;
pub mod script;
pub mod stats;
pub mod subdivision;

use anyhow::{Result, bail};
use std::path::PathBuf;
use tessd_render::{Cracks, DrawMode, Shading, UpAxis, View};

/// `--eye`, and `--target` and `--up` when given.
pub type ExplicitCamera = ([f64; 3], Option<[f64; 3]>, Option<[f64; 3]>);

/// The options of `tessd view`, parsed.
#[derive(Clone, Debug)]
pub struct Options {
    /// The files drawn.
    pub inputs: Vec<PathBuf>,
    /// Window size.
    pub size: (u32, u32),
    /// A standard view, or an explicit camera (eye, target, up).
    pub view: View,
    /// `--eye`, `--target`, `--up`.
    pub eye: Option<ExplicitCamera>,
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// The world's up axis.
    pub up_axis: UpAxis,
    /// Shading.
    pub shading: Shading,
    /// Solid, wireframe or points.
    pub mode: DrawMode,
    /// The edge overlay.
    pub edges: bool,
    /// Crack handling of B-Rep parts.
    pub cracks: Cracks,
    /// Subdivision level of meshes at the start.
    pub subdivide: u32,
    /// Frames of an animation: meshes with the cage's vertex count.
    pub frames: Vec<PathBuf>,
    /// Screen-space error of `.tsc` refinement, pixels.
    pub pixel_error: f64,
    /// `--script`.
    pub script: Option<PathBuf>,
    /// Where subdivision applies its stencils (none: the GPU when the window's adapter is
    /// one, else the CPU).
    pub subdivision_device: Option<subdivision::Device>,
}

/// `tessd view`'s command line.
#[derive(Clone, Debug, clap::Args)]
pub struct ViewArgs {
    /// Meshes (OBJ, PLY, STL, OFF, .usda), B-Rep documents (.json, OpenCASCADE .brep) and
    /// compressed meshes (.tsc), drawn in one scene.
    #[arg(required = true, num_args = 1..)]
    pub input: Vec<PathBuf>,
    /// Window size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// A standard view fitted to the scene.
    #[arg(long, default_value = "iso", value_parser = ["iso", "front", "back", "left", "right", "top", "bottom"], conflicts_with = "eye")]
    pub view: String,
    /// Explicit eye position, X,Y,Z (instead of --view).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub eye: Option<String>,
    /// The point looked at with --eye (default: the scene's centre).
    #[arg(
        long,
        value_name = "X,Y,Z",
        allow_hyphen_values = true,
        requires = "eye"
    )]
    pub target: Option<String>,
    /// The camera's up direction with --eye (default: the up axis).
    #[arg(
        long,
        value_name = "X,Y,Z",
        allow_hyphen_values = true,
        requires = "eye"
    )]
    pub up: Option<String>,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 30.0)]
    pub fov: f64,
    /// The world's up axis.
    #[arg(long, default_value = "z", value_parser = ["y", "z", "Y", "Z"])]
    pub up_axis: String,
    /// Shading.
    #[arg(long, default_value = "lit", value_parser = ["lit", "gooch", "toon", "face-ids"])]
    pub shading: String,
    /// Surfaces, wireframe or points (W cycles them).
    #[arg(long, default_value = "solid", value_parser = ["solid", "wireframe", "points"])]
    pub mode: String,
    /// Overlay the triangle edges (E).
    #[arg(long)]
    pub edges: bool,
    /// B-Rep parts: crack handling (C cycles it).
    #[arg(long, default_value = "object", value_parser = ["none", "image", "object"])]
    pub cracks: String,
    /// Start at this subdivision level (+ and - change it).
    #[arg(long, default_value_t = 0)]
    pub subdivide: u32,
    /// Frames of an animation: meshes with the cage's vertex count (Space plays them).
    #[arg(long, num_args = 1..)]
    pub frames: Vec<PathBuf>,
    /// Compressed meshes: the error allowed on screen, pixels.
    #[arg(long, default_value_t = 1.0)]
    pub pixel_error: f64,
    /// Play these actions (a JSON list) one per frame.
    #[arg(long, value_name = "ACTIONS.json")]
    pub script: Option<PathBuf>,
    /// Where subdivision applies its stencils: the GPU when the window's adapter is one, else
    /// the CPU (auto), or as asked (benchmarks compare both).
    #[arg(long, default_value = "auto", value_parser = ["auto", "cpu", "gpu"])]
    pub subdivision_device: String,
}

/// "X,Y,Z" as three finite numbers.
fn vec3(name: &str, s: &str) -> Result<[f64; 3]> {
    let xs: Vec<f64> = s
        .split(',')
        .map(|c| c.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("--{name} must be X,Y,Z, got {s:?}"))?;
    match xs.as_slice() {
        [x, y, z] if xs.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => bail!("--{name} must be three finite numbers X,Y,Z, got {s:?}"),
    }
}

impl ViewArgs {
    /// The options these arguments ask for.
    ///
    /// # Errors
    /// A size, vector or number out of range, naming its flag.
    pub fn options(self) -> Result<Options> {
        // the size rules of every other verb (`tessd render`'s limits), under the flag's name
        let (w, h) = crate::ops::params::camera::parse_size(Some(&serde_json::json!(self.size)))
            .map_err(|e| anyhow::anyhow!("--size: {}", e.message))?;
        if !(self.fov > 0.0 && self.fov < 180.0) {
            bail!("--fov must be between 0 and 180 degrees, got {}", self.fov);
        }
        if !(self.pixel_error > 0.0 && self.pixel_error.is_finite()) {
            bail!(
                "--pixel-error must be a positive number of pixels, got {}",
                self.pixel_error
            );
        }
        let eye = match &self.eye {
            Some(e) => Some((
                vec3("eye", e)?,
                self.target
                    .as_deref()
                    .map(|t| vec3("target", t))
                    .transpose()?,
                self.up.as_deref().map(|u| vec3("up", u)).transpose()?,
            )),
            None => None,
        };
        Ok(Options {
            inputs: self.input,
            size: (w, h),
            view: View::parse(&self.view).unwrap_or(View::Iso),
            eye,
            fov: self.fov,
            up_axis: UpAxis::parse(&self.up_axis.to_uppercase()).unwrap_or_default(),
            shading: Shading::parse(&self.shading).unwrap_or_default(),
            mode: DrawMode::parse(&self.mode).unwrap_or_default(),
            edges: self.edges,
            cracks: Cracks::parse(&self.cracks).unwrap_or(Cracks::Object),
            subdivide: self.subdivide,
            frames: self.frames,
            pixel_error: self.pixel_error,
            script: self.script,
            subdivision_device: match self.subdivision_device.as_str() {
                "cpu" => Some(subdivision::Device::Cpu),
                "gpu" => Some(subdivision::Device::Gpu),
                _ => None,
            },
        })
    }
}

/// The highest subdivision level `+` goes to (level 6 of a 1 000-face cage is 4 M faces).
pub const MAX_LEVEL: u32 = 6;

/// Says why there is no window to open on this machine, before anything is loaded: on Linux
/// and the BSDs, a session without `DISPLAY` or `WAYLAND_DISPLAY` has no display server.
///
/// # Errors
/// The message naming both variables and what to use instead.
pub fn check_display() -> Result<()> {
    #[cfg(all(unix, not(target_vendor = "apple")))]
    {
        let set = |k: &str| std::env::var_os(k).is_some_and(|v| !v.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            bail!(
                "tessd view needs a display: neither DISPLAY (X11) nor WAYLAND_DISPLAY is set \
                 (run it in a desktop session, under `xvfb-run`, or use `tessd render` for \
                 pictures without a window)"
            );
        }
    }
    Ok(())
}

/// Runs the viewer until its window is closed (status 0), or fails with why.
///
/// # Errors
/// No display, no adapter, a bad input (naming the file), a bad script (naming the action).
pub fn run(options: Options) -> Result<()> {
    check_display()?;
    if options.inputs.is_empty() {
        bail!("tessd view needs at least one input file");
    }
    let script = match &options.script {
        Some(p) => script::read(p)?,
        None => Vec::new(),
    };
    // every input is read and checked before a window opens
    let prepared = options
        .inputs
        .iter()
        .map(|p| items::prepare(p))
        .collect::<Result<Vec<_>>>()?;
    let frames = options
        .frames
        .iter()
        .map(|p| {
            crate::ops::mesh_arrays::read_mesh_file(p, &Default::default())
                .map_err(|e| anyhow::anyhow!("{}: {}", p.display(), e.message))
        })
        .collect::<Result<Vec<_>>>()?;
    app::run(options, prepared, frames, script)
}
