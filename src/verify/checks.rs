//! The read-only checks of [`verify_store`].

use std::collections::HashSet;
use std::path::Path;

use super::{Finding, Layer, VerifyReport};
use crate::cells::CellMesh;
use crate::store::photo_texture::atlas_blocks;
use crate::store::{CellRecord, FileRef, Manifest, crc32_hex};

/// Checks the store in `dir` (see the module documentation). Never modifies anything.
/// A manifest that cannot be read gives a report with one [`Layer::Manifest`] finding.
pub fn verify_store(dir: &Path) -> VerifyReport {
    let mut rep = VerifyReport::default();
    let manifest = match Manifest::read(dir) {
        Ok(m) => m,
        Err(e) => {
            rep.findings.push(Finding {
                cell: None,
                file: "manifest.json".into(),
                layer: Layer::Manifest,
                problem: e.to_string(),
            });
            return rep;
        }
    };
    rep.cells = manifest.cells.len();
    let mut seen = HashSet::new();
    for c in &manifest.cells {
        let mut add = |file: &str, layer: Layer, problem: String| {
            rep.findings.push(Finding {
                cell: Some(c.id.clone()),
                file: file.to_string(),
                layer,
                problem,
            })
        };
        if !seen.insert(c.id.clone()) {
            add(
                "manifest.json",
                Layer::Manifest,
                format!("cell id {} appears twice", c.id),
            );
        }
        if c.id != format!("{}-{}-{}", c.level, c.x, c.y) {
            add(
                "manifest.json",
                Layer::Manifest,
                format!(
                    "cell id {} does not match its level/x/y {}-{}-{}",
                    c.id, c.level, c.x, c.y
                ),
            );
        }
        let q = &manifest.quadtree;
        let side = 1u64 << c.level;
        if c.level >= q.levels || c.x as u64 >= side || c.y as u64 >= side {
            add(
                "manifest.json",
                Layer::Manifest,
                format!(
                    "cell {} lies outside the quadtree ({} levels)",
                    c.id, q.levels
                ),
            );
        }
    }
    for c in &manifest.cells {
        let f = &c.files;
        check_mesh(dir, c, &f.mesh, Layer::Base, false, &mut rep);
        check_png(dir, c, &f.texture, Layer::Base, c.texels, &mut rep);
        check_png(dir, c, &f.normal, Layer::Base, c.texels, &mut rep);
        if let Some(r) = &c.relief {
            check_png(dir, c, &r.file, Layer::Base, c.texels, &mut rep);
        }
        if let Some(r) = &c.reparam {
            check_mesh(dir, c, &r.files.mesh, Layer::Reparam, true, &mut rep);
            check_png(dir, c, &r.files.texture, Layer::Reparam, r.texels, &mut rep);
            check_png(dir, c, &r.files.normal, Layer::Reparam, r.texels, &mut rep);
        }
        if let Some(p) = &c.photo {
            // stored in blocks: an atlas of the blocks the mask marks
            let size = match &p.blocks {
                None => Ok((p.texels, p.texels)),
                Some(b) => b.present(p.texels).map(|present| {
                    let (cols, rows) = atlas_blocks(present.iter().filter(|&&v| v).count());
                    (cols as u32 * b.side, rows as u32 * b.side)
                }),
            };
            match size {
                Ok(size) => {
                    check_png_size(dir, c, &p.texture, Layer::Photo, size, &mut rep);
                    check_png_size(dir, c, &p.confidence, Layer::Photo, size, &mut rep);
                }
                Err(problem) => rep.findings.push(Finding {
                    cell: Some(c.id.clone()),
                    file: p.texture.path.clone(),
                    layer: Layer::Photo,
                    problem,
                }),
            }
        }
    }
    rep
}

/// Reads `f` and checks size and checksum; records a finding and returns `None` if wrong.
fn read_checked(
    dir: &Path,
    c: &CellRecord,
    f: &FileRef,
    layer: Layer,
    rep: &mut VerifyReport,
) -> Option<Vec<u8>> {
    rep.files_checked += 1;
    let mut add = |problem: String| {
        rep.findings.push(Finding {
            cell: Some(c.id.clone()),
            file: f.path.clone(),
            layer,
            problem,
        })
    };
    let bytes = match std::fs::read(dir.join(&f.path)) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            add("missing".into());
            return None;
        }
        Err(e) => {
            add(format!("cannot read: {e}"));
            return None;
        }
    };
    if bytes.len() as u64 != f.bytes {
        add(format!(
            "size {} bytes, recorded {} (truncated or overwritten)",
            bytes.len(),
            f.bytes
        ));
        return None;
    }
    let crc = crc32_hex(&bytes);
    if crc != f.crc32 {
        add(format!(
            "checksum {crc}, recorded {} (content damaged)",
            f.crc32
        ));
        return None;
    }
    Some(bytes)
}

fn check_mesh(
    dir: &Path,
    c: &CellRecord,
    f: &FileRef,
    layer: Layer,
    want_uvs: bool,
    rep: &mut VerifyReport,
) {
    let Some(bytes) = read_checked(dir, c, f, layer, rep) else {
        return;
    };
    let mut problems = Vec::new();
    match CellMesh::from_bytes(&bytes, &dir.join(&f.path)) {
        Err(e) => problems.push(e.to_string()),
        Ok(m) => {
            if m.surface_vertices != c.vertices || m.surface_triangles != c.triangles {
                problems.push(format!(
                    "surface has {} vertices / {} triangles, the manifest records {} / {}",
                    m.surface_vertices, m.surface_triangles, c.vertices, c.triangles
                ));
            }
            if let Some(t) = m
                .triangles
                .iter()
                .position(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
            {
                problems.push(format!("triangle {t} repeats a corner"));
            }
            // Surface vertices inside the recorded world bounding box (cell-local f32).
            let ns = (m.surface_vertices as usize).min(m.positions.len());
            for (i, p) in m.positions[..ns].iter().enumerate() {
                let w = [
                    p[0] as f64 + c.origin[0],
                    p[1] as f64 + c.origin[1],
                    p[2] as f64 + c.origin[2],
                ];
                let outside = (0..3).any(|k| {
                    let tol = 0.01
                        + 1e-6
                            * (c.bbox_max[k] - c.origin[k])
                                .abs()
                                .max((c.bbox_min[k] - c.origin[k]).abs());
                    w[k] < c.bbox_min[k] - tol || w[k] > c.bbox_max[k] + tol
                });
                if outside {
                    problems.push(format!(
                        "surface vertex {i} at {w:?} lies outside the cell's bounding box"
                    ));
                    break;
                }
            }
            match (&m.uvs, want_uvs) {
                (Some(uvs), true) => {
                    if let Some(i) = uvs.iter().position(|uv| {
                        !(0.0..=1.0).contains(&uv[0]) || !(0.0..=1.0).contains(&uv[1])
                    }) {
                        problems.push(format!(
                            "texture coordinate {i} {:?} outside [0, 1]",
                            uvs[i]
                        ));
                    }
                }
                (None, true) => {
                    problems.push("the reparameterized mesh has no texture coordinates".into())
                }
                (Some(_), false) => {
                    problems.push("the orthographic mesh has texture coordinates".into())
                }
                (None, false) => {}
            }
        }
    }
    for p in problems {
        rep.findings.push(Finding {
            cell: Some(c.id.clone()),
            file: f.path.clone(),
            layer,
            problem: p,
        });
    }
}

fn check_png(
    dir: &Path,
    c: &CellRecord,
    f: &FileRef,
    layer: Layer,
    side: u32,
    rep: &mut VerifyReport,
) {
    check_png_size(dir, c, f, layer, (side, side), rep)
}

/// [`check_png`] of an image of `size` (width, height).
fn check_png_size(
    dir: &Path,
    c: &CellRecord,
    f: &FileRef,
    layer: Layer,
    size: (u32, u32),
    rep: &mut VerifyReport,
) {
    let Some(bytes) = read_checked(dir, c, f, layer, rep) else {
        return;
    };
    let decoded = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .map(|i| (i.width(), i.height()));
    let problem = match decoded {
        Err(e) => Some(format!("cannot decode PNG: {e}")),
        Ok((w, h)) if (w, h) != size => Some(format!(
            "texture is {w}x{h}, the manifest records {}x{}",
            size.0, size.1
        )),
        Ok(_) => None,
    };
    if let Some(problem) = problem {
        rep.findings.push(Finding {
            cell: Some(c.id.clone()),
            file: f.path.clone(),
            layer,
            problem,
        });
    }
}
