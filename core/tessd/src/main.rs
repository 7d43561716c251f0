//! The `tessd` command line: a dispatcher from each verb to its file under [`cli`], which
//! parses the verb's arguments into a request, runs it and prints the summary.

mod cli;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// tessd — a local geometry service for CAD and DCC tools.
#[derive(Parser)]
#[command(name = "tessd", version)]
struct Cli {
    /// Worker threads for the parallel passes (simplification, ...), before or after the
    /// command; default: RAYON_NUM_THREADS, else one per core. Simplification gives the same
    /// bytes whatever it is.
    #[arg(long, global = true, value_name = "N")]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

/// The verbs, each with its arguments (defined in its file under [`cli`]).
#[derive(Subcommand)]
enum Command {
    /// Run the daemon on a local socket.
    Serve(cli::serve::ServeArgs),
    /// Run operations from job files.
    Job(cli::job::JobArgs),
    /// Print a mesh's counts, bounds and topology.
    Stats(cli::mesh_stats::StatsArgs),
    /// Convert a mesh between formats (from the extensions).
    Convert(cli::mesh_convert::ConvertArgs),
    /// Simplify a mesh by vertex clustering (regular grid, quality goal or complexity goal).
    Simplify(cli::simplify::SimplifyArgs),
    /// Subdivide a cage (uniform refinement; Catmull-Clark matches OpenSubdiv / Blender's
    /// Subdivision Surface modifier with "limit surface" off).
    Subdivide(cli::subdivide::SubdivideArgs),
    /// Build a chain of levels of detail and write them as one USD stage (and optionally one
    /// mesh file per level).
    Lod(cli::lod::LodArgs),
    /// Compress a mesh losslessly at a quantisation into a progressive .tsc file (paper 003:
    /// Gandoin-Devillers kd-tree codes in an nSP-tree).
    Compress(cli::codec::CompressArgs),
    /// Decode a .tsc file into a mesh, whole or up to a precision.
    Decompress(cli::codec::DecompressArgs),
    /// Decode what a camera needs from a .tsc file: each cell refined until its vertices'
    /// error projects within --pixel-error pixels, cells out of view left out.
    ViewDecode(cli::codec::ViewDecodeArgs),
    /// Measure the surface distance between two meshes: both one-sided distances, the
    /// symmetric Hausdorff distance and RMS (Metro-style sampling).
    Compare(cli::compare::CompareArgs),
    /// Tessellate a B-Rep (an exchange document, docs/brep-format.md, or an OpenCASCADE .brep
    /// file): each face's surface to the chordal tolerance, trimmed by its loops, shared edges
    /// discretised once (watertight).
    Tessellate(cli::tessellate::TessellateArgs),
    /// Open a window on meshes, B-Rep parts and compressed meshes: orbit, subdivide, stream
    /// (Blender's keys; H lists them; --script plays actions).
    View(tessd::view::ViewArgs),
    /// Render a mesh (OBJ, PLY, STL, OFF, USD .usda: a LOD stage's levels side by side) or a
    /// B-Rep (a .json document or an OpenCASCADE .brep file) to a PNG, headless on the GPU (lavapipe without one).
    Render(cli::render::RenderArgs),
    /// Run the main job on built-in sample data, through a real daemon, into ./tessd-demo/.
    Demo {
        /// Output folder.
        #[arg(long, default_value = "tessd-demo")]
        out: PathBuf,
    },
}

/// Mesh-sized buffers on huge pages where the kernel grants them (`tessd_mesh::allocation`).
#[global_allocator]
static ALLOCATOR: tessd_mesh::allocation::LargePages = tessd_mesh::allocation::LargePages;

fn main() {
    // Mesh-sized buffers go back to the system when a job frees them (see the module).
    tessd_mesh::allocation::return_large_buffers_to_system();
    let cli = Cli::parse();
    if !matches!(cli.command, Command::Serve(_) | Command::Demo { .. }) {
        die_quietly_on_broken_pipe();
    }
    let code = match set_threads(cli.threads).and_then(|()| run(cli)) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("tessd: {}", cli::local_run::error_text(&e));
            if e.downcast_ref::<tessd_ipc::socket::BindError>()
                .is_some_and(|b| matches!(b, tessd_ipc::socket::BindError::InUse(_)))
            {
                3
            } else {
                1
            }
        }
    };
    std::process::exit(code);
}

/// Restores SIGPIPE's default action, which Rust's runtime sets to "ignore": a CLI verb whose
/// reader goes away (`tessd stats big.ply | head -1`) then ends quietly, killed by SIGPIPE (the
/// shell shows status 141) like `cat` or `grep`, instead of panicking in `println!`. `serve`
/// keeps ignoring it, so a client that hangs up gives its socket an EPIPE error, not the daemon
/// its death; `demo` too (it talks to its daemon over a socket, and its own lines ignore a
/// closed stdout).
fn die_quietly_on_broken_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Builds the global rayon pool with `threads` workers (`--threads`); without it rayon's default
/// applies (RAYON_NUM_THREADS, else one per core).
fn set_threads(threads: Option<usize>) -> Result<()> {
    let Some(n) = threads else {
        return Ok(());
    };
    if n == 0 {
        bail!("--threads must be at least 1");
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .context("setting up the thread pool")
}

/// Hands the verb's arguments to its file under [`cli`].
fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Serve(args) => cli::serve::run(args),
        Command::Job(args) => cli::job::run(args),
        Command::Stats(args) => cli::mesh_stats::run(args),
        Command::Convert(args) => cli::mesh_convert::run(args),
        Command::Simplify(args) => cli::simplify::run(args),
        Command::Subdivide(args) => cli::subdivide::run(args),
        Command::Lod(args) => cli::lod::run(args),
        Command::Compress(args) => cli::codec::compress(args),
        Command::Decompress(args) => cli::codec::decompress(args),
        Command::ViewDecode(args) => cli::codec::view_decode(args),
        Command::Compare(args) => cli::compare::run(args),
        Command::Tessellate(args) => cli::tessellate::run(args),
        Command::View(args) => tessd::view::run(args.options()?),
        Command::Render(args) => cli::render::run(args),
        Command::Demo { out } => tessd::demo::run(&out),
    }
}
