//! A tiny Rust client of the tessd daemon (docs/protocol.md): starts `tessd serve` on a
//! private socket, a named pipe on Windows (`$TESSD_BIN`, else `tessd` on `PATH`), sends a
//! wavy 200 × 200 quad grid as arrays, asks `simplify` for 10 % of its vertices, prints the
//! reply's counts and `elapsed_ms`, and shuts the daemon down.
//!
//! Run: `cargo run --release -p tessd-example-client`
use serde_json::json;
use std::{error::Error, path::Path, process::Command, thread::sleep, time::Duration};
use tessd_ipc::{arrays::OwnedArray, client::Client};

/// An `n` × `n` grid of quads over a sine wave: positions `[n², 3]`, faces `[(n-1)², 4]`.
fn grid(n: u32) -> (Vec<[f32; 3]>, Vec<[u32; 4]>) {
    let t = |i: u32| i as f32 / (n - 1) as f32;
    let points = (0..n * n)
        .map(|v| [t(v % n), t(v / n), 0.1 * (8.0 * t(v % n)).sin()])
        .collect();
    let quads = (0..(n - 1) * (n - 1))
        .map(|f| f + f / (n - 1)) // the quad's lower-left vertex
        .map(|v| [v, v + 1, v + n + 1, v + n])
        .collect();
    (points, quads)
}

/// Connects (waiting up to 10 s for the daemon to listen), simplifies, shuts the daemon down.
fn run(socket: &Path) -> Result<(), Box<dyn Error>> {
    let mut client = Client::connect(socket);
    for _ in 0..200 {
        if client.is_ok() {
            break;
        }
        sleep(Duration::from_millis(50));
        client = Client::connect(socket);
    }
    let mut client = client?;
    let (positions, quads) = grid(200);
    let arrays = [
        OwnedArray::rows("positions", positions),
        OwnedArray::rows("face_indices", quads),
    ];
    let params = json!({"method": "complexity", "target_vertices": "10%"});
    let (report, mesh) = client.call("simplify", params, &arrays, |_| {})?;
    let names: Vec<&str> = mesh.descs().iter().map(|d| d.name.as_str()).collect();
    println!(
        "simplify: {} -> {} vertices, {} -> {} faces, surface error {}; {:.1} ms in the daemon; \
         arrays {names:?}",
        report["input_vertices"],
        report["output_vertices"],
        report["input_faces"],
        report["output_faces"],
        report["surface_error"],
        client.last_elapsed_ms().unwrap_or(f64::NAN),
    );
    client.call("shutdown", json!({}), &[], |_| {})?;
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let bin = std::env::var("TESSD_BIN").unwrap_or_else(|_| "tessd".into());
    let name = format!("tessd-rs-{}", std::process::id());
    // A socket file in the temporary folder; on Windows, where the daemon listens on named
    // pipes only, the pipe \\.\pipe\tessd-<user>-<name>.
    let socket = if cfg!(windows) {
        tessd_ipc::socket::resolve(Some(&name), false)?
    } else {
        std::env::temp_dir().join(format!("{name}.sock"))
    };
    let mut daemon = Command::new(bin)
        .args(["serve", "--socket"])
        .arg(&socket)
        .spawn()?;
    let outcome = run(&socket);
    if outcome.is_err() {
        daemon.kill()?; // `run` did not get as far as its shutdown request
    }
    daemon.wait()?;
    outcome
}
