//! The cells to export and what each one carries: its surface and skirt in world
//! coordinates (f64), texture coordinates, and its best texture's file bytes.

use glam::DVec3;

use crate::cells::CellMesh;
use crate::error::{Error, Result};
use crate::store::{CellRecord, FileRef, ReparamRecord, Store, texcoord};

/// Which texture a cell exports: the best it has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSource {
    /// The photo-enhanced texture (`cliffmap project`).
    Photo,
    /// The reparameterized texture (`cliffmap reparam`).
    Reparam,
    /// The orthographic texture.
    Ortho,
}

impl TextureSource {
    /// Position in per-source counts `[photo, reparam, ortho]`.
    pub fn index(self) -> usize {
        match self {
            TextureSource::Photo => 0,
            TextureSource::Reparam => 1,
            TextureSource::Ortho => 2,
        }
    }

    /// Lower-case name (`photo`, `reparam`, `ortho`).
    pub fn name(self) -> &'static str {
        match self {
            TextureSource::Photo => "photo",
            TextureSource::Reparam => "reparam",
            TextureSource::Ortho => "ortho",
        }
    }
}

/// One cell ready to be written: world positions (f64, the store's CRS), texture
/// coordinates (u right, v down, [0, 1], glTF's convention), surface and skirt triangles
/// (counter-clockwise seen from above / from outside), and the chosen texture's PNG bytes
/// exactly as stored.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportCell {
    /// The cell's id (`LEVEL-X-Y`).
    pub id: String,
    /// Vertex positions, world metres.
    pub positions: Vec<DVec3>,
    /// Texture coordinates per vertex.
    pub uvs: Vec<[f32; 2]>,
    /// Surface triangles.
    pub surface: Vec<[u32; 3]>,
    /// Skirt triangles.
    pub skirt: Vec<[u32; 3]>,
    /// The texture's bytes: the store's PNG file as stored, or a JPEG after
    /// [`ExportCell::texture_to_jpeg`].
    pub texture_bytes: Vec<u8>,
    /// The texture's media type, `image/png` or `image/jpeg`.
    pub texture_mime: &'static str,
    /// Which texture that is.
    pub texture: TextureSource,
    /// The cell's geometric error (metres).
    pub max_error: f64,
    /// The normal map of the mesh's texture layout (object space, the store's file).
    pub normal_file: FileRef,
    /// For the lit variant ([`ExportCell::make_lit`]): the normal map in tangent space as
    /// PNG bytes ([`super::normals`]); `None`: unlit.
    pub normal_png: Option<Vec<u8>>,
    /// Per-texel metadata as property textures ([`ExportCell::make_metadata`]); `None`:
    /// none.
    pub metadata: Option<super::metadata::CellMetadata>,
}

/// Reads a cell for export: the mesh its best texture belongs to (the reparameterized one
/// when the cell has it, else the orthographic one with texture coordinates from x, y), and
/// that texture's bytes, verified against the manifest's checksum.
pub fn read_export_cell(store: &Store, rec: &CellRecord) -> Result<ExportCell> {
    read_export_cell_as(store, rec, TextureSource::Photo)
}

/// As [`read_export_cell`] with the best texture at most `mode` (as `cliffmap render
/// --mode`): `Photo` = the best the cell has, `Reparam` = reparameterized where the cell has
/// it, else ortho, `Ortho` = the orthographic mesh and texture everywhere.
pub fn read_export_cell_as(
    store: &Store,
    rec: &CellRecord,
    mode: TextureSource,
) -> Result<ExportCell> {
    let photo = rec.photo.as_ref().filter(|_| mode == TextureSource::Photo);
    let reparam = layout_reparam(rec, mode);
    let mesh = export_mesh(store, rec, mode)?;
    let normal_file = reparam
        .map_or(&rec.files.normal, |r| &r.files.normal)
        .clone();
    let texture = export_source(rec, mode);
    let file = match (photo, reparam) {
        (Some(p), _) => &p.texture,
        (None, Some(r)) => &r.files.texture,
        (None, None) => &rec.files.texture,
    };
    let texture_bytes = match photo {
        // stored in blocks: the whole texture, encoded again
        Some(p) if p.blocks.is_some() => crate::fsutil::encode_png(
            &store.dir.join(&p.texture.path),
            &store.read_photo_texture(rec, p)?.0,
            crate::fsutil::PngCompression::default(),
        )?,
        _ => store.read_file(file)?,
    };
    let positions = world_positions(rec, &mesh);
    let uvs: Vec<[f32; 2]> = (0..mesh.positions.len())
        .map(|i| texcoord(rec, &mesh, i))
        .collect();
    let n = mesh.positions.len() as u32;
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&i| i >= n)) {
        return Err(Error::store(
            store.dir.join(&rec.files.mesh.path),
            format!("triangle {t:?} indexes past {n} vertices"),
        ));
    }
    let split = (mesh.surface_triangles as usize).min(mesh.triangles.len());
    Ok(ExportCell {
        id: rec.id.clone(),
        positions,
        uvs,
        surface: mesh.triangles[..split].to_vec(),
        skirt: mesh.triangles[split..].to_vec(),
        texture_bytes,
        texture_mime: "image/png",
        texture,
        max_error: rec.max_error,
        normal_file,
        normal_png: None,
        metadata: None,
    })
}

/// The mesh a cell is exported with in `mode` (the reparameterized one where the cell has it
/// and `mode` is not `Ortho`, else the orthographic one), verified.
fn export_mesh(store: &Store, rec: &CellRecord, mode: TextureSource) -> Result<CellMesh> {
    match layout_reparam(rec, mode) {
        Some(r) => store.read_mesh_file(&r.files.mesh),
        None => store.read_mesh(rec),
    }
}

/// The reparameterized variant whose mesh and texture layout a cell is exported with in
/// `mode`: the cell's, unless it has none or `mode` is `Ortho`.
fn layout_reparam(rec: &CellRecord, mode: TextureSource) -> Option<&ReparamRecord> {
    rec.reparam
        .as_ref()
        .filter(|_| mode != TextureSource::Ortho)
}

/// The texture a cell is exported with in `mode`: its photo texture when it has one and
/// `mode` is `Photo`, else its reparameterized one where [`layout_reparam`] gives one, else
/// the orthographic one.
fn export_source(rec: &CellRecord, mode: TextureSource) -> TextureSource {
    match (&rec.photo, layout_reparam(rec, mode), mode) {
        (Some(_), _, TextureSource::Photo) => TextureSource::Photo,
        (_, Some(_), _) => TextureSource::Reparam,
        _ => TextureSource::Ortho,
    }
}

/// The world positions (the store's CRS, f64) of `mesh`, a mesh of cell `rec`.
fn world_positions(rec: &CellRecord, mesh: &CellMesh) -> Vec<DVec3> {
    let origin = DVec3::from_array(rec.origin);
    mesh.positions
        .iter()
        .map(|p| origin + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect()
}

/// The world positions of the mesh [`read_export_cell_as`] exports for `rec` in `mode`, and
/// the texture source it would embed, without reading the texture.
pub fn read_export_positions(
    store: &Store,
    rec: &CellRecord,
    mode: TextureSource,
) -> Result<(Vec<DVec3>, TextureSource)> {
    let mesh = export_mesh(store, rec, mode)?;
    Ok((world_positions(rec, &mesh), export_source(rec, mode)))
}

impl ExportCell {
    /// Prepares the per-texel metadata ([`super::metadata`]) of cell `rec` exported in
    /// `mode` (the mode this cell was read with): the stretch of its mesh's texture layout
    /// and, when it carries its photo texture, the photo share.
    pub fn make_metadata(
        &mut self,
        store: &Store,
        rec: &CellRecord,
        mode: TextureSource,
    ) -> Result<()> {
        let mesh = export_mesh(store, rec, mode)?;
        let texels = layout_reparam(rec, mode).map_or(rec.texels, |r| r.texels);
        let uvs = rec.surface_texcoords(&mesh);
        let stretch = crate::stats::cell_texel_stretch(&mesh, &uvs, rec.base_area(), texels);
        let path = store.dir.join(&self.normal_file.path);
        let png = crate::fsutil::PngCompression::default();
        let stretch_png = crate::fsutil::encode_png(
            &path,
            &super::metadata::stretch_image(&stretch, texels),
            png,
        )?;
        let share_png = match (&rec.photo, self.texture) {
            (Some(p), TextureSource::Photo) => Some(crate::fsutil::encode_png(
                &path,
                &store.read_photo_confidence(p)?,
                png,
            )?),
            _ => None,
        };
        self.metadata = Some(super::metadata::CellMetadata {
            stretch_png,
            share_png,
        });
        Ok(())
    }

    /// Prepares the lit variant: the cell's normal map (read from `store`, verified) baked
    /// into the tangent space of its surface's vertex frames ([`super::normals`]), as PNG.
    pub fn make_lit(&mut self, store: &Store) -> Result<()> {
        let map = store.read_png(&self.normal_file)?.to_rgb8();
        let frames = super::normals::vertex_frames(&self.positions, &self.uvs, &self.surface);
        let baked = super::normals::bake_tangent_normals(&map, &self.uvs, &self.surface, &frames);
        self.normal_png = Some(crate::fsutil::encode_png(
            &store.dir.join(&self.normal_file.path),
            &baked,
            crate::fsutil::PngCompression::default(),
        )?);
        Ok(())
    }

    /// Re-encodes the colour texture as a baseline JPEG of `quality` (1..=100) from its RGB;
    /// alpha is dropped (the exported materials are opaque, so it is never shown). Errors
    /// name the cell.
    pub fn texture_to_jpeg(&mut self, quality: u8) -> Result<()> {
        let bad = |e: String| Error::BadOption(format!("cell {}: texture to JPEG: {e}", self.id));
        let rgb = image::load_from_memory_with_format(&self.texture_bytes, image::ImageFormat::Png)
            .map_err(|e| bad(e.to_string()))?
            .to_rgb8();
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality.clamp(1, 100))
            .encode_image(&rgb)
            .map_err(|e| bad(e.to_string()))?;
        self.texture_bytes = out;
        self.texture_mime = "image/jpeg";
        Ok(())
    }
}

/// Which cells to export.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellSelection {
    /// A quadtree level (0 = root); `None` with `max_error` `None`: the finest level.
    pub level: Option<u8>,
    /// The coarsest level whose every cell's error is at most this (metres).
    pub max_error: Option<f64>,
    /// Only cells whose extent meets this rectangle `[x0, y0, x1, y1]` (world metres).
    pub region: Option<[f64; 4]>,
}

/// The manifest indices of the cells `sel` picks, in manifest order. Errors for a level the
/// store does not have, an error no level reaches, or a region that meets no cell.
pub fn select_cells(store: &Store, sel: &CellSelection) -> Result<Vec<usize>> {
    let levels = store.manifest.quadtree.levels;
    let level = match (sel.level, sel.max_error) {
        (Some(l), _) if l >= levels => {
            return Err(Error::BadOption(format!(
                "level {l} is not in store {} (levels 0..{levels})",
                store.dir.display()
            )));
        }
        (Some(l), _) => l,
        (None, Some(m)) => (0..levels)
            .find(|&l| {
                store
                    .manifest
                    .cells
                    .iter()
                    .filter(|c| c.level == l)
                    .all(|c| c.max_error <= m)
            })
            .ok_or_else(|| {
                Error::BadOption(format!(
                    "no level of store {} has every cell's error within {m} m",
                    store.dir.display()
                ))
            })?,
        (None, None) => levels.saturating_sub(1),
    };
    let meets = |c: &CellRecord| match sel.region {
        None => true,
        Some([x0, y0, x1, y1]) => {
            c.extent.min_x <= x1
                && c.extent.max_x >= x0
                && c.extent.min_y <= y1
                && c.extent.max_y >= y0
        }
    };
    let picked: Vec<usize> = store
        .manifest
        .cells
        .iter()
        .enumerate()
        .filter(|(_, c)| c.level == level && meets(c))
        .map(|(i, _)| i)
        .collect();
    if picked.is_empty() {
        return Err(Error::BadOption(format!(
            "no cell of level {level} meets the region {:?}",
            sel.region
        )));
    }
    Ok(picked)
}
