//! Protocol benchmark (issue 2): round trip of a large mesh through a real daemon over the
//! local socket, beside a raw Unix-socket echo of the same number of bytes in the same run;
//! and loading a large binary PLY beside a plain read of the file.
//!
//! Run: `cargo run --release -p tessd --example bench_ipc -- [TRIANGLES_M] [PLY_TRIANGLES_M]`
//! (defaults 5 and 10). Prints a Markdown table; `bench/run_ipc.sh` stores it in `bench/`.
//!
//! Unix only: its baseline is a Unix-socket echo and its memory figure is /proc's `VmHWM`; on
//! Windows it only says so (the shared helpers are then unused).
#![cfg_attr(not(unix), allow(dead_code, unused_imports))]

use serde_json::json;
use std::io::{Read, Write};
#[cfg(unix)]
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::Path;
use std::time::{Duration, Instant};
use tessd::ops::mesh_arrays::mesh_to_arrays;
use tessd_ipc::client::Client;
use tessd_ipc::server::{Server, ServerOptions};
use tessd_mesh::Mesh;

/// A grid of `n × n` quads split into triangles, gently waved so it is not planar.
fn grid(n: u32) -> Mesh {
    let mut m = Mesh::default();
    let s = 1.0 / n as f32;
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 * s, j as f32 * s);
            m.positions
                .push([x, y, 0.05 * (7.0 * x).sin() * (5.0 * y).cos()]);
        }
    }
    m.face_indices.reserve(6 * (n * n) as usize);
    m.face_offsets.reserve(2 * (n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            m.push_face(&[v, v + 1, v + n + 2]);
            m.push_face(&[v, v + n + 2, v + n + 1]);
        }
    }
    m
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Peak resident memory of this process so far, in MiB (Linux `VmHWM`).
fn peak_rss_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Raw baseline: send `bytes` to an echo thread over a Unix socket and read them back.
#[cfg(unix)]
fn raw_echo(dir: &Path, bytes: &[u8]) -> Duration {
    let path = dir.join("raw.sock");
    let _ = std::fs::remove_file(&path);
    let listener = UnixListener::bind(&path).unwrap();
    let n = bytes.len();
    let echo = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut buf = vec![0u8; n];
        s.read_exact(&mut buf).unwrap();
        s.write_all(&buf).unwrap();
    });
    let t = Instant::now();
    let mut s = UnixStream::connect(&path).unwrap();
    let mut back = vec![0u8; n];
    std::thread::scope(|scope| {
        let mut w = s.try_clone().unwrap();
        scope.spawn(move || w.write_all(bytes).unwrap());
        s.read_exact(&mut back).unwrap();
    });
    let d = t.elapsed();
    echo.join().unwrap();
    assert!(back == bytes);
    d
}

/// Child mode: `bench_ipc load FILE` loads the file and prints its peak RSS in MiB, so the
/// loader's memory is measured in a process that did nothing else.
fn load_child(path: &str) {
    let m = tessd_mesh::io::read_path(Path::new(path), &Default::default()).unwrap();
    std::hint::black_box(&m);
    println!("{:.1}", peak_rss_mib());
}

#[cfg(not(unix))]
fn main() {
    eprintln!("bench_ipc compares with a Unix-socket echo and reads /proc: it runs on Unix only");
}

#[cfg(unix)]
fn main() {
    if let [_, mode, path] = &std::env::args().collect::<Vec<_>>()[..]
        && mode == "load"
    {
        return load_child(path);
    }
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a number"))
        .collect();
    let tris_m = args.first().copied().unwrap_or(5.0);
    let ply_m = args.get(1).copied().unwrap_or(10.0);
    let dir = tempfile::tempdir().unwrap();
    let runs = 5;

    // --- socket round trip ---------------------------------------------------------------
    let n = ((tris_m * 1e6 / 2.0).sqrt()) as u32;
    let mesh = grid(n);
    let triangles = mesh.face_count();
    let socket = dir.path().join("bench.sock");
    let listener = tessd_ipc::socket::bind(&socket).unwrap();
    let server = Server::new(
        listener,
        &socket,
        tessd::ops::registry(),
        ServerOptions::default(),
    );
    let stop = server.shutdown_handle();
    let serving = std::thread::spawn(move || server.serve().unwrap());
    let mut client = Client::connect(&socket).unwrap();
    let arrays = mesh_to_arrays(mesh.clone());
    let sent: usize = arrays.iter().map(|a| a.bytes().len()).sum();
    let mut raw_bytes = Vec::with_capacity(sent);
    for a in &arrays {
        raw_bytes.extend_from_slice(a.bytes());
    }
    let (mut t_echo, mut t_proto, mut t_raw) = (Vec::new(), Vec::new(), Vec::new());
    let mut received = 0;
    for _ in 0..runs {
        let t = Instant::now();
        let (_, back) = client
            .call("debug.echo", json!({}), &arrays, |_| {})
            .unwrap();
        t_echo.push(t.elapsed().as_secs_f64());
        assert_eq!(back.bytes("positions").unwrap(), arrays[0].bytes());
        let t = Instant::now();
        let (_, back) = client
            .call("mesh.convert", json!({}), &arrays, |_| {})
            .unwrap();
        t_proto.push(t.elapsed().as_secs_f64());
        received = back.payload_len();
        t_raw.push(raw_echo(dir.path(), &raw_bytes).as_secs_f64());
    }
    assert_eq!(received, sent.next_multiple_of(8).max(received));
    let mb = (sent + received) as f64 / 1e6;
    let (e, p, r) = (median(t_echo), median(t_proto), median(t_raw));
    println!(
        "## Socket round trip: {triangles} triangles, {:.1} MB each way, median of {runs}\n",
        sent as f64 / 1e6
    );
    println!("| path | time (ms) | throughput (MB/s, both ways) |\n|---|---|---|");
    println!(
        "| tessd `debug.echo`: frames only, the protocol's own cost | {:.1} | {:.0} |",
        e * 1e3,
        mb / e
    );
    println!(
        "| tessd `mesh.convert` → arrays: frames + building and validating the mesh | {:.1} | {:.0} |",
        p * 1e3,
        mb / p
    );
    println!(
        "| raw Unix-socket echo of the same bytes | {:.1} | {:.0} |",
        r * 1e3,
        mb / r
    );
    println!(
        "\nratio tessd / raw throughput: **{:.2}** for `debug.echo` (the protocol), {:.2} for `mesh.convert`\n",
        r / e,
        r / p
    );
    stop.trigger();
    serving.join().unwrap();

    // --- 10 M-triangle binary PLY load -------------------------------------------------------
    drop((arrays, raw_bytes, client));
    let n = ((ply_m * 1e6 / 2.0).sqrt()) as u32;
    let big = grid(n);
    let ply = dir.path().join("big.ply");
    tessd_mesh::io::write_path(&big, &ply).unwrap();
    let mesh_bytes =
        big.positions.len() * 12 + big.face_indices.len() * 4 + big.face_offsets.len() * 4;
    drop(big);
    let file_mb = std::fs::metadata(&ply).unwrap().len() as f64 / 1e6;
    let (mut t_load, mut t_read) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        let t = Instant::now();
        let m = tessd_mesh::io::read_path(&ply, &Default::default()).unwrap();
        t_load.push(t.elapsed().as_secs_f64());
        std::hint::black_box(m);
        let t = Instant::now();
        let bytes = std::fs::read(&ply).unwrap();
        t_read.push(t.elapsed().as_secs_f64());
        std::hint::black_box(bytes);
    }
    let (l, rd) = (median(t_load), median(t_read));
    let child = std::process::Command::new(std::env::current_exe().unwrap())
        .arg("load")
        .arg(&ply)
        .output()
        .unwrap();
    let load_rss: f64 = String::from_utf8_lossy(&child.stdout)
        .trim()
        .parse()
        .unwrap_or(f64::NAN);
    println!(
        "## Binary PLY load: {} triangles, {file_mb:.0} MB file, median of 3 (file in page cache)\n",
        2 * n * n
    );
    println!("| path | time (ms) | MB/s |\n|---|---|---|");
    println!(
        "| `tessd_mesh::io::read_path` (parse + validate) | {:.0} | {:.0} |",
        l * 1e3,
        file_mb / l
    );
    println!(
        "| `std::fs::read` of the file | {:.0} | {:.0} |",
        rd * 1e3,
        file_mb / rd
    );
    let mesh_mib = mesh_bytes as f64 / 1048576.0;
    println!("\nratio load / plain read time: **{:.2}**", l / rd);
    println!(
        "\npeak RSS of a process that only loads the file: {load_rss:.0} MiB; the mesh itself: {mesh_mib:.0} MiB (ratio {:.2})",
        load_rss / mesh_mib
    );
}
