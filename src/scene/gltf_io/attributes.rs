//! Vertex attributes read as floats from every component type glTF allows
//! for them: `FLOAT`, and under KHR_mesh_quantization (gltfpack's default
//! output) signed and unsigned bytes and shorts, normalised or not. The
//! `gltf` crate's readers take floats alone for positions and normals.
//! And the morph targets' displacements added at their default weights.

use gltf::accessor::{DataType, Item, Iter};

/// The extension that lets positions, normals and texture coordinates be
/// integers.
pub const MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

/// A component as a float: normalised integers map to [0, 1] (unsigned)
/// or [−1, 1] (signed, the most negative value clamped), glTF 2.0 §3.11;
/// others keep their value.
fn component(value: f32, max: f32, normalized: bool) -> f32 {
    if normalized {
        (value / max).max(-1.0)
    } else {
        value
    }
}

/// The elements of `accessor` (sparse substitutions applied) as float
/// arrays, integers normalised where the accessor says so or
/// `normalized_anyway` (core glTF's integer texture coordinates, which must
/// be normalised, also where a file forgets the flag); `None` where its
/// component type is not one of the five above or its buffer is missing
/// (the caller's accessor checks come first).
pub fn read_floats<const N: usize>(
    accessor: gltf::Accessor,
    buffers: &[gltf::buffer::Data],
    normalized_anyway: bool,
) -> Option<Vec<[f32; N]>>
where
    [f32; N]: Item,
    [i8; N]: Item,
    [u8; N]: Item,
    [i16; N]: Item,
    [u16; N]: Item,
{
    let data = |b: gltf::Buffer| buffers.get(b.index()).map(|d| d.0.as_slice());
    let normalized = accessor.normalized() || normalized_anyway;
    fn floats<T: Copy, const N: usize>(
        items: Iter<'_, [T; N]>,
        to_f32: impl Fn(T) -> f32,
    ) -> Vec<[f32; N]>
    where
        [T; N]: Item,
    {
        items.map(|v| v.map(&to_f32)).collect()
    }
    Some(match accessor.data_type() {
        DataType::F32 => Iter::<[f32; N]>::new(accessor, data)?.collect(),
        DataType::I8 => floats(Iter::<[i8; N]>::new(accessor, data)?, |c| {
            component(c as f32, i8::MAX as f32, normalized)
        }),
        DataType::U8 => floats(Iter::<[u8; N]>::new(accessor, data)?, |c| {
            component(c as f32, u8::MAX as f32, normalized)
        }),
        DataType::I16 => floats(Iter::<[i16; N]>::new(accessor, data)?, |c| {
            component(c as f32, i16::MAX as f32, normalized)
        }),
        DataType::U16 => floats(Iter::<[u16; N]>::new(accessor, data)?, |c| {
            component(c as f32, u16::MAX as f32, normalized)
        }),
        DataType::U32 => return None,
    })
}

/// The primitive's rest pose where its mesh has morph targets: each
/// target's position and normal displacements added at the mesh's default
/// weight (glTF 2.0 § 3.7.2.2, "Morph Targets"), normals made unit again.
/// A target whose displacements do not match the vertices, or whose weight
/// is not finite, is skipped with a warning; a node's own `weights` are not
/// read.
pub fn add_default_morph(
    file: &str,
    mesh: &gltf::Mesh,
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    positions: &mut [glam::Vec3],
    normals: &mut [glam::Vec3],
) {
    let weights = mesh.weights().unwrap_or_default();
    let mut normals_turned = false;
    for (t, (target, &w)) in prim.morph_targets().zip(weights).enumerate() {
        if !w.is_finite() {
            log::warn!(
                "{file}: mesh '{}': morph target {t}'s default weight is {w}; drawn without it",
                mesh.name().unwrap_or_default()
            );
        }
        if w == 0.0 || !w.is_finite() {
            continue;
        }
        let read = |a: Option<gltf::Accessor>| a.and_then(|a| read_floats::<3>(a, buffers, false));
        let moved = read(target.positions());
        let turned = read(target.normals());
        let fits = |d: &Option<Vec<[f32; 3]>>, n: usize| d.as_ref().is_none_or(|d| d.len() == n);
        if !fits(&moved, positions.len()) || !fits(&turned, normals.len()) {
            log::warn!(
                "{file}: mesh '{}': morph target {t}'s displacements do not match its vertices; drawn without it",
                mesh.name().unwrap_or_default()
            );
            continue;
        }
        let add = |v: &mut [glam::Vec3], d: Option<Vec<[f32; 3]>>| {
            for (v, d) in v.iter_mut().zip(d.iter().flatten()) {
                *v += w * glam::Vec3::from(*d);
            }
        };
        normals_turned |= turned.is_some();
        add(positions, moved);
        add(normals, turned);
    }
    // The reader made them unit already; only displaced ones need it again.
    if normals_turned {
        for n in normals.iter_mut() {
            *n = n.normalize_or_zero();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Normalised components span [0, 1] or [−1, 1], the most negative
    /// signed value clamped to −1; others keep their integer value.
    #[test]
    fn normalised_components_map_to_unit_ranges() {
        assert_eq!(component(255.0, 255.0, true), 1.0);
        assert_eq!(component(-128.0, 127.0, true), -1.0);
        assert_eq!(component(-32767.0, 32767.0, true), -1.0);
        assert_eq!(component(16384.0, 32767.0, true), 16384.0 / 32767.0);
        assert_eq!(component(-300.0, 32767.0, false), -300.0);
    }
}
