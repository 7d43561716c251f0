//! `tessd demo`: the main job on bundled sample data, end to end through a real daemon.
//!
//! It starts `tessd serve` as a child process on a private socket, sends the bundled Spot mesh
//! as arrays over the socket, asks for its statistics, a USD file and an LOD chain (50 %, 20 %
//! and 5 % of its vertices, as a USD variant set `LOD`), and writes them to the output folder.
//! Later stages (subdivision, B-Rep) extend this list.

use anyhow::{Context, Result, bail};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tessd_ipc::client::Client;
use tessd_mesh::io::{Format, ReadOptions};

/// Spot (Keenan Crane, public domain), triangulated, with UVs.
pub const SPOT_OBJ: &[u8] = include_bytes!("../data/spot_triangulated.obj");

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
    let socket = socket_dir.join("demo.sock");
    println!("tessd demo: starting a daemon on {}", socket.display());
    let daemon = Daemon::start(&socket)?;
    let mut client = Client::connect(&daemon.socket)?;

    let (hello, _) = client.call("hello", json!({}), &[], |_| {})?;
    println!(
        "  daemon {} (protocol {}), ops: {}",
        hello["version"], hello["protocol"], hello["ops"]
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
    println!(
        "  mesh.stats: {} vertices, {} faces, {} boundary edges -> {}",
        stats["vertices"],
        stats["faces"],
        stats["boundary_edges"],
        stats_path.display()
    );

    let usd_path = out.join("spot.usda");
    let (converted, _) =
        client.call("mesh.convert", json!({"output": usd_path}), &arrays, |_| {})?;
    println!(
        "  mesh.convert: {} vertices, {} faces -> {}",
        converted["vertices"],
        converted["faces"],
        usd_path.display()
    );

    let lods_path = out.join("spot_lods.usda");
    let (lods, _) = client.call(
        "lod",
        json!({"output": lods_path, "levels": ["50%", "20%", "5%"], "name": "spot"}),
        &arrays,
        |_| {},
    )?;
    let counts: Vec<String> = lods["levels"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|l| l["output_vertices"].to_string())
        .collect();
    println!(
        "  lod: LOD0 {} vertices, LOD1..{} {} vertices -> {}",
        lods["input_vertices"],
        counts.len(),
        counts.join(" / "),
        lods_path.display()
    );
    drop(daemon);
    let _ = std::fs::remove_dir_all(&socket_dir);
    println!("tessd demo: done, results in {}", out.display());
    Ok(())
}

/// A fresh private folder for the demo's socket, so the demo never meets a user's daemon.
fn tempdir_for_socket() -> Result<PathBuf> {
    let base = tessd_ipc::socket::default_dir(true)?;
    let dir = base.join(format!("demo-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
