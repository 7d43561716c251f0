//! `tessd demo`: the main job on bundled sample data, end to end through a real daemon.
//!
//! It starts `tessd serve` as a child process on a private socket, sends the bundled Spot mesh
//! as arrays over the socket, asks for its statistics, a USD file and an LOD chain (50 %, 20 %
//! and 5 % of its vertices, as a USD variant set `LOD`); then sends Spot's quad cage and asks
//! for its Catmull–Clark surface (the refined mesh, the cage marked `catmullClark`, and a
//! 24-frame animation refined with one topology phase), and writes everything to the output
//! folder; and OpenCASCADE's bottle as B-Rep faces (exported by `python -m tessd.brep`),
//! tessellated to 0.1 mm into a USD file with one GeomSubset per face. Last, pictures through
//! the `render` op: the bottle with paper 001's object-space crack filling (and its face ids),
//! and each level of Spot's LOD chain from one camera.
//!
//! Without any GPU adapter (no Vulkan driver at all, not even lavapipe) everything but the
//! pictures is still written; the demo then ends with one line naming the pictures it could not
//! render and the command that installs the software driver, and fails.

use anyhow::{Context, Result, bail};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tessd_ipc::arrays::{Arrays, OwnedArray};
use tessd_ipc::client::{Client, ClientError};
use tessd_mesh::io::{Format, ReadOptions};

/// `println!` that ignores a closed stdout (`tessd demo | head -3`): the demo's lines report
/// on the files, which it still writes to the end.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// Spot (Keenan Crane, public domain), triangulated, with UVs.
pub const SPOT_OBJ: &[u8] = include_bytes!("../data/spot_triangulated.obj");

/// Spot's control mesh (quads, a few triangles and pentagons), with UVs: a subdivision cage.
pub const SPOT_CAGE_OBJ: &[u8] = include_bytes!("../data/spot_control_mesh.obj");

/// OpenCASCADE's bottle (OCCT `data/occ/bottle.brep`), 71 faces in the tessd-brep format.
pub const BOTTLE_JSON: &[u8] = include_bytes!("../../tessellate/tests/data/bottle.json");

/// Frames of the demo's animation.
const FRAMES: usize = 24;

/// Stops the child daemon however the demo ends.
struct Daemon {
    child: Child,
    socket: PathBuf,
}

impl Daemon {
    fn start(socket: &Path) -> Result<Daemon> {
        let exe = std::env::current_exe().context("locating the tessd binary")?;
        let child = Command::new(exe)
            .args(["serve", "--socket"])
            .arg(socket)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            // The daemon's routine lines (listening, a failed render) would interleave with the
            // demo's report, which says all of it; warnings and errors still show.
            .env(
                "TESSD_LOG",
                std::env::var("TESSD_LOG").unwrap_or_else(|_| "warn".into()),
            )
            .stderr(Stdio::inherit())
            .spawn()
            .context("starting tessd serve")?;
        let mut daemon = Daemon {
            child,
            socket: socket.to_path_buf(),
        };
        let deadline = Instant::now() + Duration::from_secs(10);
        while tessd_ipc::socket::connect(socket).is_err() {
            if let Some(status) = daemon.child.try_wait()? {
                bail!("tessd serve exited early ({status})");
            }
            if Instant::now() > deadline {
                bail!(
                    "tessd serve did not answer on {} within 10 s",
                    socket.display()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        Ok(daemon)
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        if let Ok(mut c) = Client::connect(&self.socket) {
            let _ = c.call("shutdown", json!({}), &[], |_| {});
        }
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs the demo, writing into `out`.
///
/// # Errors
/// When the daemon cannot start or a request fails.
pub fn run(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let out = out.canonicalize()?;
    let socket_dir = tempdir_for_socket()?;
    // Windows: the daemon listens on named pipes only; a pipe name of this process's own.
    let socket = if cfg!(windows) {
        tessd_ipc::socket::resolve(Some(&format!("demo-{}", std::process::id())), false)?
    } else {
        socket_dir.join("demo.sock")
    };
    say!("tessd demo: starting a daemon on {}", socket.display());
    let daemon = Daemon::start(&socket)?;
    let mut client = Client::connect(&daemon.socket)?;

    let (hello, _) = client.call("hello", json!({}), &[], |_| {})?;
    say!(
        "  daemon {} (protocol {}), ops: {}",
        hello["version"],
        hello["protocol"],
        hello["ops"]
    );

    let mesh = tessd_mesh::io::read(
        SPOT_OBJ,
        Format::Obj,
        "spot_triangulated.obj",
        &ReadOptions::default(),
    )?;
    let arrays = crate::ops::mesh_arrays::mesh_to_arrays(mesh);
    let (stats, _) = client.call("mesh.stats", json!({}), &arrays, |_| {})?;
    let stats_path = out.join("spot_stats.json");
    std::fs::write(&stats_path, serde_json::to_string_pretty(&stats)? + "\n")?;
    say!(
        "  mesh.stats: {} vertices, {} faces, {} boundary edges -> {}",
        stats["vertices"],
        stats["faces"],
        stats["boundary_edges"],
        stats_path.display()
    );

    let usd_path = out.join("spot.usda");
    let (converted, _) =
        client.call("mesh.convert", json!({"output": usd_path}), &arrays, |_| {})?;
    say!(
        "  mesh.convert: {} vertices, {} faces -> {}",
        converted["vertices"],
        converted["faces"],
        usd_path.display()
    );

    let lods_path = out.join("spot_lods.usda");
    let (lods, lod_arrays) = client.call(
        "lod",
        json!({
            "output": lods_path,
            "levels": ["50%", "20%", "5%"],
            "name": "spot",
            "return_arrays": true,
        }),
        &arrays,
        |_| {},
    )?;
    let counts: Vec<String> = lods["levels"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|l| l["output_vertices"].to_string())
        .collect();
    say!(
        "  lod: LOD0 {} vertices, LOD1..{} {} vertices -> {}",
        lods["input_vertices"],
        counts.len(),
        counts.join(" / "),
        lods_path.display()
    );
    subdivision(&mut client, &out)?;
    tessellation(&mut client, &out)?;
    let mut levels = vec![arrays];
    for i in 1..=counts.len() {
        levels.push(level_arrays(&lod_arrays, i)?);
    }
    let rendered = render_bottle(&mut client, &out)
        .and_then(|()| render_lods(&mut client, &out, &levels, &lods_path));
    drop(daemon);
    let _ = std::fs::remove_dir_all(&socket_dir);
    if let Err(e) = rendered {
        let Some(reason) = no_adapter(&e) else {
            return Err(e);
        };
        let missing: Vec<&str> = PICTURES
            .iter()
            .copied()
            .filter(|p| !out.join(p).exists())
            .collect();
        say!("  render: no GPU adapter ({reason})");
        bail!(
            "no GPU adapter, so {} of the demo's pictures were not rendered ({}); everything else \
             is in {}. Install the software Vulkan driver (lavapipe), as root: `{}`, and run the \
             demo again",
            missing.len(),
            missing.join(", "),
            out.display(),
            tessd_gpu::SOFTWARE_DRIVER_INSTALL
        );
    }
    say!("tessd demo: done, results in {}", out.display());
    Ok(())
}

/// The pictures the demo renders, in order: all it needs a GPU adapter for.
pub const PICTURES: [&str; 7] = [
    "bottle.png",
    "bottle_face_ids.png",
    "spot_lod0.png",
    "spot_lod1.png",
    "spot_lod2.png",
    "spot_lod3.png",
    "spot_lods.png",
];

/// wgpu's reason when `e` is the daemon's answer that it has no GPU adapter at all
/// ([`tessd_gpu::GpuError::NoAdapter`]), else `None`.
fn no_adapter(e: &anyhow::Error) -> Option<String> {
    let ClientError::Op(op) = e.downcast_ref::<ClientError>()? else {
        return None;
    };
    let rest = op.message.strip_prefix(tessd_gpu::NO_ADAPTER)?;
    let reason = rest.strip_prefix(" (").unwrap_or(rest);
    Some(
        reason
            .rsplit_once("); ")
            .map_or(reason, |(r, _)| r)
            .to_string(),
    )
}

/// Spot's cage subdivided three ways: the refined mesh, the cage for USD renderers to refine,
/// and an animation (a wave through the cage) refined frame by frame on one set of tables.
fn subdivision(client: &mut Client, out: &Path) -> Result<()> {
    let cage = tessd_mesh::io::read(
        SPOT_CAGE_OBJ,
        Format::Obj,
        "spot_control_mesh.obj",
        &ReadOptions::default(),
    )?;
    let frames: Vec<f32> = (0..FRAMES)
        .flat_map(|k| {
            let phase = std::f32::consts::TAU * k as f32 / FRAMES as f32;
            cage.positions
                .iter()
                .flat_map(move |p| [p[0], p[1], p[2] + 0.05 * (6.0 * p[0] + phase).sin()])
        })
        .collect();
    let v = cage.positions.len() as u64;
    let arrays = crate::ops::mesh_arrays::mesh_to_arrays(cage);
    let refined = out.join("spot_subdiv.usda");
    let (r, _) = client.call(
        "subdivide",
        json!({"output": refined, "levels": 3, "name": "spot"}),
        &arrays,
        |_| {},
    )?;
    say!(
        "  subdivide: cage {} faces -> {} faces at level 3 (topology {:.1} ms, apply {:.1} ms) -> {}",
        r["cage_faces"],
        r["faces"],
        r["topology_ms"].as_f64().unwrap_or(0.0),
        r["apply_ms"].as_f64().unwrap_or(0.0),
        refined.display()
    );
    let cage_path = out.join("spot_cage.usda");
    client.call(
        "subdivide",
        json!({"output": cage_path, "usd": "cage", "levels": 3, "name": "spot"}),
        &arrays,
        |_| {},
    )?;
    say!(
        "  subdivide: the cage with subdivisionScheme = \"catmullClark\" -> {}",
        cage_path.display()
    );
    let mut with_frames = arrays;
    with_frames.push(OwnedArray::new("frames", vec![FRAMES as u64, v, 3], frames));
    let anim = out.join("spot_subdiv_anim.usda");
    let (r, _) = client.call(
        "subdivide",
        json!({"output": anim, "levels": 2, "name": "spot"}),
        &with_frames,
        |_| {},
    )?;
    say!(
        "  subdivide: {} frames at level 2, one topology phase ({:.1} ms), apply {:.2} ms per frame -> {}",
        r["frames"],
        r["topology_ms"].as_f64().unwrap_or(0.0),
        r["apply_ms_per_frame"].as_f64().unwrap_or(0.0),
        anim.display()
    );
    Ok(())
}

/// The bottle's B-Rep faces, checked (`brep.load`) and tessellated to 0.1 mm.
fn tessellation(client: &mut Client, out: &Path) -> Result<()> {
    let doc: serde_json::Value = serde_json::from_slice(BOTTLE_JSON)?;
    let (loaded, _) = client.call("brep.load", json!({"brep": doc}), &[], |_| {})?;
    say!(
        "  brep.load: bottle, {} faces, {}",
        loaded["faces"].as_array().map_or(0, Vec::len),
        loaded["stats"]["faces_by_surface"]
    );
    let usd = out.join("bottle.usda");
    let (r, _) = client.call(
        "tessellate",
        json!({"brep": doc, "tolerance": "0.1mm", "output": usd, "name": "bottle"}),
        &[],
        |_| {},
    )?;
    say!(
        "  tessellate: {} faces -> {} triangles at 0.1 mm in {:.0} ms -> {}",
        r["faces"],
        r["triangles"],
        r["time_ms"].as_f64().unwrap_or(0.0),
        usd.display()
    );
    Ok(())
}

/// The bottle rendered through paper 001's pipeline with object-space crack filling, and its
/// face ids (one colour code per B-Rep face).
fn render_bottle(client: &mut Client, out: &Path) -> Result<()> {
    let doc: serde_json::Value = serde_json::from_slice(BOTTLE_JSON)?;
    let png = out.join("bottle.png");
    let ids = out.join("bottle_face_ids.png");
    let (r, _) = client.call(
        "render",
        json!({
            "brep": doc, "cracks": "object", "size": "1280x720", "view": "iso",
            "output": png, "face_ids": ids,
        }),
        &[],
        |_| {},
    )?;
    say!(
        "  render: bottle {}x{} iso, {} cracks detected / {} filled (object), {} of {} pixels covered, {:.0} ms -> {}",
        r["width"],
        r["height"],
        r["cracks"]["detected"],
        r["cracks"]["filled"],
        r["covered"],
        r["pixels"],
        r["timings_ms"]["total"].as_f64().unwrap_or(0.0),
        png.display()
    );
    say!("  render: bottle face ids -> {}", ids.display());
    Ok(())
}

/// Where the LOD pictures look from: Spot is Y up, seen from the front left and above.
const SPOT_EYE: [f64; 3] = [-2.6, 1.2, -3.6];
const SPOT_TARGET: [f64; 3] = [0.0, 0.1, 0.2];

/// Each level of Spot's LOD chain (`levels[0]` the input), from one camera, so the pictures
/// compare directly; then the whole chain side by side from the USD stage the `lod` op wrote
/// (`stage`: one panel per LOD variant).
fn render_lods(
    client: &mut Client,
    out: &Path,
    levels: &[Vec<OwnedArray>],
    stage: &Path,
) -> Result<()> {
    for (i, arrays) in levels.iter().enumerate() {
        let png = out.join(format!("spot_lod{i}.png"));
        let (r, _) = client.call(
            "render",
            json!({
                "size": "640x480", "eye": SPOT_EYE, "target": SPOT_TARGET, "up": [0.0, 1.0, 0.0],
                "output": png,
            }),
            arrays,
            |_| {},
        )?;
        say!(
            "  render: Spot LOD{i}, {} triangles, {} of {} pixels covered -> {}",
            r["triangles"],
            r["covered"],
            r["pixels"],
            png.display()
        );
    }
    let png = out.join("spot_lods.png");
    let (r, _) = client.call(
        "render",
        json!({
            "input": stage, "size": "320x320", "eye": SPOT_EYE, "target": SPOT_TARGET,
            "up": [0.0, 1.0, 0.0], "output": png,
        }),
        &[],
        |_| {},
    )?;
    let panels: Vec<String> = r["panels"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|p| format!("{} {}", p["label"].as_str().unwrap_or(""), p["triangles"]))
        .collect();
    say!(
        "  render: Spot's LOD chain side by side from {} ({}), {}x{} -> {}",
        stage.display(),
        panels.join(" / "),
        r["width"],
        r["height"],
        png.display()
    );
    Ok(())
}

/// LOD level `i`'s mesh from the `lod` op's `lod<i>.*` arrays, under the plain mesh-array names
/// (positions and faces: all the render op needs).
fn level_arrays(arrays: &Arrays, i: usize) -> Result<Vec<OwnedArray>> {
    let mut level = Vec::new();
    let positions = format!("lod{i}.positions");
    let (p, shape) = arrays
        .get::<f32>(&positions)
        .with_context(|| format!("the lod op returned no `{positions}`"))?
        .map_err(anyhow::Error::msg)?;
    level.push(OwnedArray::new("positions", shape.to_vec(), p.to_vec()));
    for name in ["face_indices", "face_sizes"] {
        let key = format!("lod{i}.{name}");
        let (v, shape) = arrays
            .get::<u32>(&key)
            .with_context(|| format!("the lod op returned no `{key}`"))?
            .map_err(anyhow::Error::msg)?;
        level.push(OwnedArray::new(name, shape.to_vec(), v.to_vec()));
    }
    Ok(level)
}

/// A fresh private folder for the demo's socket, so the demo never meets a user's daemon.
fn tempdir_for_socket() -> Result<PathBuf> {
    let base = tessd_ipc::socket::default_dir(true)?;
    let dir = base.join(format!("demo-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
