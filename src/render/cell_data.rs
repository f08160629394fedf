//! What a cell needs on the GPU, prepared off the render thread: mesh, UV stream, colour
//! and normal mip chains (colour averaged in linear light), geomorphing targets.

use crate::cells::CellMesh;
use crate::store::{CellRecord, texcoord};

/// A cell's data ready for upload, produced off the render thread.
#[derive(Clone, Debug)]
pub struct CellData {
    /// The mesh (positions cell-local f32).
    pub mesh: CellMesh,
    /// Per-vertex texture coordinates when drawn with the UV pipeline, else `None`.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Colour texture, full mip chain (level 0 first, down to 1×1, averaged in linear light),
    /// sRGB RGBA8.
    pub colour_mips: Vec<image::RgbaImage>,
    /// Normal map (RGB in the cell-local frame, n·0.5+0.5, A = 255), full mip chain.
    pub normal_mips: Vec<image::RgbaImage>,
    /// The cell's relief map (encoded heights of the DEM above the TIN, orthographic layout
    /// over the nominal square, whatever the texture's layout), for relief mapping
    /// ([`CellData::set_relief`]); `None`: none.
    pub relief: Option<image::GrayImage>,
    /// Largest height of [`CellData::relief`], metres (0: no relief mapping).
    pub relief_m: f32,
    /// Triangles whose unit normal has a smaller up component are not relief-mapped
    /// ([`crate::cells::relief::ORTHO_MIN_NORMAL_Z`] or `CHART_MIN_NORMAL_Z`).
    pub relief_min_normal_z: f32,
    /// Per vertex, how far relief mapping may move a lookup, metres
    /// ([`crate::cells::relief_reach()`]); `None`: unbounded (orthographic layouts).
    pub relief_reach: Option<Vec<f32>>,
    /// For a chart drawn with its photo texture: the chart's own (reparameterized) texture's
    /// mip chain, whose share of each photo texel (the photo texture's alpha, `1 − s`) is
    /// relief-mapped; `None` otherwise.
    pub base_mips: Option<Vec<image::RgbaImage>>,
    /// For a chart with relief mapping: its cell's orthographic texture's mip chain, read
    /// where it resolves the surface more finely than the chart; `None` otherwise.
    pub ortho_mips: Option<Vec<image::RgbaImage>>,
    /// Geomorphing data (towards the parent cell), when the scene morphs and the cell has a parent.
    pub morph: Option<MorphData>,
}

/// What a cell needs to be morphed towards its parent (see [`super::geomorph`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MorphData {
    /// Per vertex (surface and skirt): the target height in the cell-local frame (metres) and
    /// the parent's texture coordinates of the same surface point, `[z, u, v]`.
    pub targets: Vec<[f32; 3]>,
    /// LOD shift of the colour texture to the parent's texel density, mip levels (≥ 0), used
    /// when the parent's textures are not resident.
    pub colour_shift: f32,
    /// LOD shift of the normal map to the parent's, mip levels (≥ 0), likewise.
    pub normal_shift: f32,
}

/// How texture coordinates are produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UvMode {
    /// Per cell: the reparameterized variant (stored UVs) where the cell has one, else the
    /// orthographic files with UVs derived in the vertex shader (correct rendering).
    Mixed,
    /// Every cell uses its orthographic files, UVs derived from x, y (the baseline).
    Ortho,
    /// Like `Mixed`, but every cell reads a UV vertex stream (computed on the CPU for cells
    /// without stored UVs).
    Reparam,
    /// Like `Mixed`, with each cell's photo-enhanced texture (`rec.photo`) where it has one:
    /// every cell's best texture (the default of [`super::SceneOptions`]).
    Photo,
}

impl CellData {
    /// Builds upload data: generates the mip chains (2 × 2 box averages, colour in linear
    /// light; each level half the previous, at least 1 texel) and the UV stream `mode` calls
    /// for.
    pub fn new(
        rec: &CellRecord,
        mesh: CellMesh,
        colour: image::RgbaImage,
        normal: image::RgbImage,
        mode: UvMode,
    ) -> CellData {
        let uvs = match mode {
            UvMode::Ortho => None,
            UvMode::Mixed | UvMode::Photo => mesh.uvs.clone(),
            UvMode::Reparam => Some(
                (0..mesh.positions.len())
                    .map(|k| texcoord(rec, &mesh, k))
                    .collect(),
            ),
        };
        let normal = image::DynamicImage::ImageRgb8(normal).to_rgba8();
        CellData {
            mesh,
            uvs,
            colour_mips: colour_mip_chain(colour),
            normal_mips: mip_chain(normal),
            relief: None,
            relief_m: 0.0,
            relief_min_normal_z: 1.0,
            relief_reach: None,
            base_mips: None,
            ortho_mips: None,
            morph: None,
        }
    }

    /// Sets the cell's relief map for relief mapping of triangles whose unit normal's up
    /// component is at least `min_normal_z` (the limit of the drawn texture's layout). On a
    /// chart (`chart`: the texture coordinates are a reparameterization) lookups move at most
    /// each vertex's reach ([`crate::cells::relief_reach()`]) over the nominal square `width`
    /// metres wide. A map of range 0 or without texels is ignored.
    pub fn set_relief(
        &mut self,
        relief: crate::cells::ReliefMap,
        min_normal_z: f32,
        chart: bool,
        width: f64,
    ) {
        let (rw, rh) = relief.image.dimensions();
        if !(relief.range_m > 0.0) || rw == 0 || rh == 0 {
            return;
        }
        if chart && self.uvs.is_some() {
            let cap = crate::cells::relief::max_shift_m(width, rw);
            self.relief_reach = Some(crate::cells::relief_reach(
                &self.mesh.positions,
                self.mesh.surface(),
                min_normal_z,
                cap,
            ));
        }
        self.relief = Some(relief.image);
        self.relief_m = relief.range_m as f32;
        self.relief_min_normal_z = min_normal_z;
    }
}

/// Puts into each texel's alpha of a photo-enhanced `texture` the share of the chart's own
/// texture in its colour, `255 − confidence` (the photo's share; 0..255 = 0..1), which relief
/// mapping moves (docs/rendering.md, "Charts"). Fails if the two images differ in size.
pub fn set_base_share(
    texture: &mut image::RgbaImage,
    confidence: &image::GrayImage,
) -> std::result::Result<(), String> {
    if texture.dimensions() != confidence.dimensions() {
        return Err(format!(
            "confidence map of {:?} texels for a photo texture of {:?}",
            confidence.dimensions(),
            texture.dimensions()
        ));
    }
    for (t, c) in texture.pixels_mut().zip(confidence.pixels()) {
        t.0[3] = 255 - c.0[0];
    }
    Ok(())
}

/// The full mip chain of `img` (level 0 = `img`): each level the previous one's 2 × 2 box
/// average (a last odd row or column joins the previous block: 3 texels are averaged), down
/// to 1 × 1, as stored data (normal maps).
pub fn mip_chain(img: image::RgbaImage) -> Vec<image::RgbaImage> {
    mip_chain_in(img, crate::colour::ColourSpace::Srgb)
}

/// [`mip_chain`] of a colour texture, RGB averaged in linear light (alpha as it is): what an
/// sRGB texture's filtering assumes.
pub fn colour_mip_chain(img: image::RgbaImage) -> Vec<image::RgbaImage> {
    mip_chain_in(img, crate::colour::ColourSpace::Linear)
}

fn mip_chain_in(img: image::RgbaImage, space: crate::colour::ColourSpace) -> Vec<image::RgbaImage> {
    let mut out = vec![img];
    loop {
        let last = &out[out.len() - 1];
        let (w, h) = last.dimensions();
        if w <= 1 && h <= 1 {
            return out;
        }
        let next = halve(last, space);
        out.push(next);
    }
}

/// One mip step: texel `(i, j)` of the `max(1, w/2) × max(1, h/2)` result averages the
/// source texels `2i..2i+2` (plus the last column if `w` is odd and `i` is the last) by
/// `2j..2j+2` likewise, RGB in `space`, alpha as values.
fn halve(img: &image::RgbaImage, space: crate::colour::ColourSpace) -> image::RgbaImage {
    let (w, h) = img.dimensions();
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let span = |i: u32, n: u32, len: u32| -> std::ops::Range<u32> {
        let a = (2 * i).min(len - 1);
        let b = if i + 1 == n {
            len
        } else {
            (2 * i + 2).min(len)
        };
        a..b
    };
    image::RgbaImage::from_fn(nw, nh, |i, j| {
        let mut acc = [0.0f32; 4];
        let mut count = 0.0f32;
        for y in span(j, nh, h) {
            for x in span(i, nw, w) {
                let p = img.get_pixel(x, y).0;
                for k in 0..3 {
                    acc[k] += space.decode_u8(p[k]);
                }
                acc[3] += p[3] as f32;
                count += 1.0;
            }
        }
        image::Rgba([
            space.encode_u8(acc[0] / count),
            space.encode_u8(acc[1] / count),
            space.encode_u8(acc[2] / count),
            (acc[3] / count + 0.5) as u8,
        ])
    })
}
