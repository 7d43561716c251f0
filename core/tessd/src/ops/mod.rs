//! The daemon's operations: thin adapters (parse, validate, call the library, encode) filled
//! into the [`Registry`] that the server and job files share.

pub mod brep_load;
pub mod codec;
pub mod common;
pub mod compare;
pub mod debug_echo;
pub mod debug_sleep;
pub mod library_errors;
pub mod lod;
pub mod mesh_arrays;
pub mod mesh_convert;
pub mod mesh_stats;
pub mod params;
pub mod render;
pub mod simplify;
pub mod subdivide;
pub mod tessellate;
pub mod trim_classify;

use tessd_ipc::registry::Registry;

/// Every operation of this build, and the capabilities `hello` reports.
pub fn registry() -> Registry {
    let mut r = Registry::new();
    r.register("mesh.stats", mesh_stats::run)
        .register("mesh.convert", mesh_convert::run)
        .register("simplify", simplify::run)
        .register("lod", lod::run)
        .register("compare", compare::run)
        .register("subdivide", subdivide::run)
        .register("brep.load", brep_load::run)
        .register("tessellate", tessellate::run)
        .register("trim.classify", trim_classify::run)
        .register("render", render::run)
        .register("codec.compress", codec::compress)
        .register("codec.decompress", codec::decompress)
        .register("codec.view", codec::view)
        .register("debug.sleep", debug_sleep::run)
        .register("debug.echo", debug_echo::run);
    for cap in [
        "mesh.read.obj",
        "mesh.read.ply",
        "mesh.read.stl",
        "mesh.read.off",
        "mesh.write.obj",
        "mesh.write.ply",
        "mesh.write.stl",
        "mesh.write.off",
        "usd.read.usda",
        "usd.write.usda",
        "usd.lod.variants",
        "usd.lod.usdlod",
        "brep.format.1",
        "render.png",
        "progress",
        "cancel",
    ] {
        r.add_capability(cap);
    }
    r
}
