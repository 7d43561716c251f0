//! Daemons started at the same moment on one socket (the workers of a node, each asking for the
//! node's daemon): exactly one binds, the others are told it is in use, and the socket file
//! leads to the one that bound. Before `bind` took its start lock, a late starter could take the
//! winner's fresh socket file (created, not yet listening) for stale and delete it. On Windows
//! the starters race for a named pipe's first instance instead.

use interprocess::local_socket::traits::Listener as _;
use std::sync::{Arc, Barrier};
use tessd_ipc::socket::{BindError, bind, connect};

/// Round `round`'s endpoint: a socket file in `dir`; on Windows a pipe name of this process
/// (there the pipe's first instance, not a file, decides who serves).
fn endpoint(dir: &std::path::Path, round: u32) -> std::path::PathBuf {
    if cfg!(windows) {
        let _ = dir;
        format!(r"\\.\pipe\tessd-bind-race-{}-{round}", std::process::id()).into()
    } else {
        dir.join(format!("r{round}.sock"))
    }
}

#[test]
fn simultaneous_starts_leave_one_reachable_daemon() {
    let dir = tempfile::tempdir().unwrap();
    for round in 0..150 {
        let path = endpoint(dir.path(), round);
        let starters = 6;
        let barrier = Arc::new(Barrier::new(starters));
        let handles: Vec<_> = (0..starters)
            .map(|_| {
                let (path, barrier) = (path.clone(), barrier.clone());
                std::thread::spawn(move || {
                    barrier.wait();
                    bind(&path)
                })
            })
            .collect();
        let results: Vec<_> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        let mut winners = Vec::new();
        for r in results {
            match r {
                Ok(listener) => winners.push(listener),
                Err(BindError::InUse(_)) => {}
                Err(e) => panic!("round {round}: {e}"),
            }
        }
        assert_eq!(
            winners.len(),
            1,
            "round {round}: {} daemons bound",
            winners.len()
        );
        // The socket file reaches the winner: its accept returns our connection.
        let listener = winners.pop().unwrap();
        let client = std::thread::spawn({
            let path = path.clone();
            move || connect(&path).map(|_| ())
        });
        listener
            .accept()
            .expect("the winner accepts the connection");
        client.join().unwrap().expect("the socket connects");
    }
}
