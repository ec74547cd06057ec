//! Test support: the GPU interface declared in Rust against its WGSL
//! declaration. naga reflects a WGSL struct's member offsets and size, and
//! [`assert_struct_matches`] compares them with the `#[repr(C)]` Rust struct
//! that fills it, so the two cannot drift apart unnoticed.

/// `source` as a naga module; a parse error is the test's failure.
fn parse(source: &str) -> naga::Module {
    naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("WGSL does not parse: {}", e.emit_to_string(source)))
}

/// The members (name, byte offset) and the size of the WGSL struct `name`
/// in `source`.
pub fn wgsl_struct(source: &str, name: &str) -> (Vec<(String, u32)>, u32) {
    let module = parse(source);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the WGSL"));
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let fields = members
        .iter()
        .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
        .collect();
    (fields, layouter[handle].size)
}

/// The global variables of bind group `group` in `source`: (name, binding).
pub fn wgsl_bindings(source: &str, group: u32) -> Vec<(String, u32)> {
    let module = parse(source);
    module
        .global_variables
        .iter()
        .filter_map(|(_, v)| {
            let b = v.binding.as_ref()?;
            (b.group == group).then(|| (v.name.clone().unwrap_or_default(), b.binding))
        })
        .collect()
}

/// Asserts that the WGSL struct `name` has exactly the members `rust`
/// (name, `offset_of!`) in order and the Rust struct's `size`.
pub fn assert_struct_matches(source: &str, name: &str, rust: &[(&str, usize)], size: usize) {
    let (wgsl, wgsl_size) = wgsl_struct(source, name);
    let rust: Vec<(String, u32)> = rust
        .iter()
        .map(|(n, o)| (n.to_string(), *o as u32))
        .collect();
    assert_eq!(
        wgsl, rust,
        "{name}: WGSL members (left) against the Rust struct's (right)"
    );
    assert_eq!(
        wgsl_size as usize, size,
        "{name}: WGSL size against the Rust struct's"
    );
}

/// `(field, offset_of!(T, field))` for each field named.
#[macro_export]
macro_rules! field_offsets {
    ($t:ty; $($f:ident),+ $(,)?) => {
        &[$((stringify!($f), std::mem::offset_of!($t, $f))),+]
    };
}

/// The value of the integer `const` `name` of `source` (after naga's
/// constant evaluation, so `1u << K` is folded).
pub fn wgsl_const_u32(source: &str, name: &str) -> u32 {
    let module = parse(source);
    let (_, constant) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no const {name} in the WGSL"));
    match module.global_expressions[constant.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => v,
        naga::Expression::Literal(naga::Literal::I32(v)) => v as u32,
        naga::Expression::Literal(naga::Literal::AbstractInt(v)) => v as u32,
        ref e => panic!("const {name} is not an integer literal: {e:?}"),
    }
}

/// Asserts that each WGSL `const` (name, the Rust value) of `source` has the
/// value its Rust declaration gives.
pub fn assert_consts_match(source: &str, rust: &[(&str, u32)]) {
    for &(name, value) in rust {
        assert_eq!(
            wgsl_const_u32(source, name),
            value,
            "const {name}: WGSL (left) against Rust (right)"
        );
    }
}
