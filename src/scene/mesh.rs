//! Indexed triangle meshes: welding, flat and double-sided copies, smooth
//! normals and tangents.

use super::Aabb;
use anyhow::{Result, bail};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// An indexed triangle mesh in object space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    /// Linear RGB per vertex that multiplies the material's colour (glTF
    /// `COLOR_0`); empty: white.
    pub colors: Vec<Vec3>,
    /// xyz tangent, w handedness (±1), derived from the uvs.
    pub tangents: Vec<Vec4>,
    pub indices: Vec<u32>,
    /// [`Mesh::make_double_sided`] added the back faces: the second half of
    /// the vertices and triangles mirrors the first.
    pub sides_doubled: bool,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Appends `other` transformed by `m` (normals by its inverse transpose).
    pub fn append(&mut self, other: &Mesh, m: Mat4) {
        let base = self.positions.len() as u32;
        let nm = m.inverse().transpose();
        self.positions
            .extend(other.positions.iter().map(|&p| m.transform_point3(p)));
        self.normals.extend(
            other
                .normals
                .iter()
                .map(|&n| nm.transform_vector3(n).normalize_or_zero()),
        );
        self.uvs.extend_from_slice(&other.uvs);
        if !(self.colors.is_empty() && other.colors.is_empty()) {
            self.colors.resize(base as usize, Vec3::ONE);
            self.colors.extend_from_slice(&other.colors);
            self.colors
                .resize(base as usize + other.positions.len(), Vec3::ONE);
        }
        self.tangents.extend(other.tangents.iter().map(|t| {
            m.transform_vector3(t.truncate())
                .normalize_or_zero()
                .extend(t.w)
        }));
        self.indices.extend(other.indices.iter().map(|&i| i + base));
    }

    /// Validates the mesh and fills in what is missing: an error on NaN or
    /// infinite positions or out-of-range indices; degenerate triangles are
    /// dropped (the count is returned); missing normals become smooth
    /// area-weighted normals, missing uvs zero, colours of another count (or
    /// not finite) white; tangents are derived from uvs.
    pub fn finalize(&mut self) -> Result<usize> {
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            bail!(
                "mesh '{}': vertex {} has a non-finite position {:?}",
                self.name,
                i,
                self.positions[i]
            );
        }
        if !self.indices.len().is_multiple_of(3) {
            bail!(
                "mesh '{}': index count {} is not a multiple of 3",
                self.name,
                self.indices.len()
            );
        }
        let n = self.positions.len() as u32;
        if let Some(&bad) = self.indices.iter().find(|&&i| i >= n) {
            bail!(
                "mesh '{}': index {} out of range ({} vertices)",
                self.name,
                bad,
                n
            );
        }
        let before = self.indices.len() / 3;
        let pos = &self.positions;
        let kept: Vec<u32> = self
            .indices
            .chunks_exact(3)
            .filter(|t| {
                let (a, b, c) = (pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
                t[0] != t[1]
                    && t[1] != t[2]
                    && t[0] != t[2]
                    && (b - a).cross(c - a).length_squared() > 0.0
            })
            .flatten()
            .copied()
            .collect();
        let degenerate = before - kept.len() / 3;
        self.indices = kept;
        if self.normals.len() != self.positions.len() || self.normals.iter().any(|n| !n.is_finite())
        {
            self.normals = smooth_normals(&self.positions, &self.indices);
        }
        if self.uvs.len() != self.positions.len() {
            self.uvs = vec![Vec2::ZERO; self.positions.len()];
        }
        if self.colors.len() != self.positions.len() || self.colors.iter().any(|c| !c.is_finite()) {
            self.colors.clear();
        }
        self.tangents = compute_tangents(&self.positions, &self.normals, &self.uvs, &self.indices);
        Ok(degenerate)
    }

    /// Splits every triangle into its own three vertices with the face normal
    /// (OBJ `s off`, flat-shaded geometry).
    pub fn unweld_flat(&mut self) {
        let mut out = Mesh {
            name: self.name.clone(),
            ..Default::default()
        };
        for t in self.indices.chunks_exact(3) {
            let p: Vec<Vec3> = t.iter().map(|&i| self.positions[i as usize]).collect();
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            for (k, &i) in t.iter().enumerate() {
                out.positions.push(p[k]);
                out.normals.push(n);
                out.uvs
                    .push(self.uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
                if let Some(&c) = self.colors.get(i as usize) {
                    out.colors.push(c);
                }
                out.indices.push(out.indices.len() as u32);
            }
        }
        *self = out;
    }

    /// Adds a copy of every triangle with the opposite winding and normal,
    /// so that a thin open surface is visible and lit from both sides.
    pub fn make_double_sided(&mut self) {
        self.sides_doubled = true;
        let n = self.positions.len() as u32;
        self.positions.extend_from_within(..);
        let flipped: Vec<Vec3> = self.normals.iter().map(|&v| -v).collect();
        self.normals.extend(flipped);
        self.uvs.extend_from_within(..);
        self.colors.extend_from_within(..);
        // The back copy's normal is flipped; flipping the handedness keeps
        // its bitangent `cross(n, t)·w` and so its normal map the same.
        let back_tangents: Vec<Vec4> = self
            .tangents
            .iter()
            .map(|t| t.truncate().extend(-t.w))
            .collect();
        self.tangents.extend(back_tangents);
        let back: Vec<u32> = self
            .indices
            .chunks_exact(3)
            .flat_map(|t| [t[0] + n, t[2] + n, t[1] + n])
            .collect();
        self.indices.extend(back);
    }

    /// The same surface with every triangle's winding reversed (normals and
    /// tangents kept). Placed by a mirroring transform (negative
    /// determinant), it is wound counter-clockwise seen from outside again,
    /// as culling and shadow-volume counting assume; the scene shader flips
    /// the tangent handedness by the sign of the determinant.
    pub fn with_reversed_winding(&self) -> Mesh {
        let mut m = self.clone();
        for t in m.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        m.name = format!("{} (mirrored)", self.name);
        m
    }

    /// The mesh as authored: without the back faces
    /// [`Mesh::make_double_sided`] added.
    pub fn single_sided(&self) -> Mesh {
        if !self.sides_doubled {
            return self.clone();
        }
        let (nv, nt) = (self.positions.len() / 2, self.indices.len() / 2);
        Mesh {
            name: self.name.clone(),
            positions: self.positions[..nv].to_vec(),
            normals: self.normals[..nv].to_vec(),
            uvs: self.uvs[..nv].to_vec(),
            colors: self.colors[..nv.min(self.colors.len())].to_vec(),
            tangents: self.tangents[..nv.min(self.tangents.len())].to_vec(),
            indices: self.indices[..nt].to_vec(),
            sides_doubled: false,
        }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }
}

/// Area-weighted vertex normals, accumulated over vertices welded by
/// position so that seams (duplicated vertices) shade smoothly.
pub fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut weld: std::collections::HashMap<[u32; 3], usize> = Default::default();
    let slot: Vec<usize> = positions
        .iter()
        .map(|p| {
            let next = weld.len();
            *weld.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    let mut n = vec![Vec3::ZERO; weld.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        let fnrm = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for v in [a, b, c] {
            n[slot[v]] += fnrm;
        }
    }
    slot.iter()
        .map(|&s| n[s].try_normalize().unwrap_or(Vec3::Y))
        .collect()
}

/// Per-vertex tangents from uv derivatives (Lengyel's method), Gram-Schmidt
/// orthogonalised against the normal, handedness in w.
pub fn compute_tangents(p: &[Vec3], n: &[Vec3], uv: &[Vec2], indices: &[u32]) -> Vec<Vec4> {
    let mut tan = vec![Vec3::ZERO; p.len()];
    let mut bit = vec![Vec3::ZERO; p.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        let (e1, e2) = (p[b] - p[a], p[c] - p[a]);
        let (d1, d2) = (uv[b] - uv[a], uv[c] - uv[a]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-12 {
            continue;
        }
        let r = 1.0 / det;
        let sdir = (e1 * d2.y - e2 * d1.y) * r;
        let tdir = (e2 * d1.x - e1 * d2.x) * r;
        for &v in &[a, b, c] {
            tan[v] += sdir;
            bit[v] += tdir;
        }
    }
    (0..p.len())
        .map(|i| {
            let nn = n[i];
            let t = (tan[i] - nn * nn.dot(tan[i]))
                .try_normalize()
                .unwrap_or_else(|| nn.any_orthonormal_vector());
            let w = if nn.cross(t).dot(bit[i]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            t.extend(w)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::scene::shapes;

    #[test]
    fn double_sided_meshes_keep_a_tangent_per_vertex() {
        let mut m = shapes::plane(2.0, 2.0, 2);
        m.finalize().unwrap();
        let n = m.positions.len();
        m.make_double_sided();
        assert_eq!(m.tangents.len(), 2 * n);
        assert_eq!(m.normals.len(), 2 * n);
        // Same tangent, opposite handedness on the back copy.
        assert_eq!(m.tangents[n].truncate(), m.tangents[0].truncate());
        assert_eq!(m.tangents[n].w, -m.tangents[0].w);
    }
}
