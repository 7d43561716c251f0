//! Test support: a pass's WGSL parsed and validated by naga without a device, and the sizes
//! of its structs, so a layout that drifts from the Rust side fails on any machine.

use wgpu::naga;

/// The module of `source`, which must parse and validate.
pub(crate) fn validated(source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source).expect("WGSL parses");
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .expect("WGSL validates");
    module
}

/// The byte size of the struct `name` in `module`.
pub(crate) fn struct_size(module: &naga::Module, name: &str) -> usize {
    let (_, t) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the shader"));
    t.inner.size(module.to_ctx()) as usize
}
