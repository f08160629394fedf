//! The binary cell mesh (`.mesh` files): cell-local f32 positions, optional f32 texture
//! coordinates, u32 triangles, surface first and skirt after it: the file format of
//! [`CellMesh`] (the type itself is the cells stage's).
//!
//! Layout (little endian), version 1:
//! ```text
//! magic   8 bytes  b"CLIFMESH"
//! version u32      1
//! flags   u32      bit 0: texture coordinates present
//! n_vertices u32, n_triangles u32            (all, surface + skirt)
//! n_surface_vertices u32, n_surface_triangles u32
//! positions  n_vertices * 3 f32            (cell-local metres: x east, y north, z up)
//! uvs        n_vertices * 2 f32 if flag 0 (u east, v south, in [0,1])
//! triangles  n_triangles * 3 u32           (CCW seen from outside/above)
//! ```

use std::path::Path;

use crate::cells::CellMesh;
use crate::error::{Error, Result};

const MAGIC: &[u8; 8] = b"CLIFMESH";
const VERSION: u32 = 1;
const HEADER: usize = 8 + 4 * 6;

impl CellMesh {
    /// Serializes to the version-1 binary layout.
    pub fn to_bytes(&self) -> Vec<u8> {
        let nv = self.positions.len();
        let mut out = Vec::with_capacity(HEADER + nv * 20 + self.triangles.len() * 12);
        out.extend_from_slice(MAGIC);
        let flags = u32::from(self.uvs.is_some());
        for v in [
            VERSION,
            flags,
            nv as u32,
            self.triangles.len() as u32,
            self.surface_vertices,
            self.surface_triangles,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for p in &self.positions {
            for c in p {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        if let Some(uvs) = &self.uvs {
            for t in uvs {
                for c in t {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        for t in &self.triangles {
            for i in t {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
        out
    }

    /// Parses the binary layout; `path` is only used in error messages. Rejects wrong magic,
    /// unknown versions, truncated data, out-of-range indices and non-finite values.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<CellMesh> {
        let bad = |m: &str| Error::store(path, format!("mesh file: {m}"));
        if bytes.len() < HEADER || &bytes[..8] != MAGIC {
            return Err(bad("not a cliffmap mesh (bad magic or too short)"));
        }
        let word = |i: usize| {
            u32::from_le_bytes([
                bytes[8 + 4 * i],
                bytes[9 + 4 * i],
                bytes[10 + 4 * i],
                bytes[11 + 4 * i],
            ])
        };
        let (version, flags, nv, nt, sv, st) = (
            word(0),
            word(1),
            word(2) as usize,
            word(3) as usize,
            word(4),
            word(5),
        );
        if version != VERSION {
            return Err(bad(&format!(
                "unsupported version {version} (this cliffmap reads {VERSION})"
            )));
        }
        let has_uv = flags & 1 == 1;
        let need = HEADER as u64 + nv as u64 * if has_uv { 20 } else { 12 } + nt as u64 * 12;
        if bytes.len() as u64 != need {
            return Err(bad(&format!(
                "size {} bytes, header announces {need}",
                bytes.len()
            )));
        }
        if sv as usize > nv || st as usize > nt {
            return Err(bad("surface counts exceed totals"));
        }
        let mut at = HEADER;
        let mut f32s = |n: usize| -> Vec<f32> {
            let v = bytes[at..at + 4 * n]
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            at += 4 * n;
            v
        };
        let pos = f32s(nv * 3);
        let uv = has_uv.then(|| f32s(nv * 2));
        if pos
            .iter()
            .chain(uv.iter().flatten())
            .any(|c| !c.is_finite())
        {
            return Err(bad("non-finite coordinate"));
        }
        let tri_bytes = &bytes[HEADER + 4 * (pos.len() + uv.as_ref().map_or(0, Vec::len))..];
        let idx: Vec<u32> = tri_bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if idx.iter().any(|&i| i as usize >= nv) {
            return Err(bad("triangle index out of range"));
        }
        Ok(CellMesh {
            positions: pos.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            uvs: uv.map(|u| u.chunks_exact(2).map(|c| [c[0], c[1]]).collect()),
            triangles: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            surface_vertices: sv,
            surface_triangles: st,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_rejects_corruption() {
        let m = CellMesh {
            positions: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 2.0], [0.0, 1.0, 3.0]],
            uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [0.0, 0.0]]),
            triangles: vec![[0, 1, 2]],
            surface_vertices: 3,
            surface_triangles: 1,
        };
        let b = m.to_bytes();
        let p = Path::new("x.mesh");
        assert_eq!(CellMesh::from_bytes(&b, p).unwrap(), m);
        assert!(CellMesh::from_bytes(&b[..b.len() - 1], p).is_err());
        let mut bad = b.clone();
        let n = bad.len();
        bad[n - 4..].copy_from_slice(&9u32.to_le_bytes());
        assert!(CellMesh::from_bytes(&bad, p).is_err());
        assert!(CellMesh::from_bytes(b"garbage", p).is_err());
    }
}
