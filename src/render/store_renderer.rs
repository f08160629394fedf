//! A store opened for rendering: LOD selection, streaming, GPU cache and frames.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::DVec3;

use super::cache::LruCache;
use super::camera::RenderCamera;
use super::cell_data::{colour_mip_chain, set_base_share};
use super::distortion::{DistortedView, DistortionMode};
use super::geomorph::{GeomorphOptions, mip_shift, morph_factor, morph_targets};
use super::gpu::{
    CellData, CellDraw, FrameOptions, GpuCell, GpuContext, MorphData, TerrainRenderer, UvMode,
};
use super::lod::{
    CellIndex, distance_to_bbox, geometric_error, screen_space_error, select_cells_with_margin,
};
use super::overlay::{NO_PHOTO_COLOUR, Overlay, share_map, stretch_heatmap};
use super::stream::{Streamer, resolve_draw_list};
use crate::camera::CameraModel;
use crate::cells::CellMesh;
use crate::error::{Error, Result};
use crate::store::{CellRecord, Store, texcoord};

/// How a scene renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneOptions {
    /// Screen-space error threshold in pixels (refine while above).
    pub sse_px: f64,
    /// GPU memory budget for cached cells, bytes.
    pub budget_bytes: u64,
    /// Texture-coordinate mode (and texture source); default [`UvMode::Photo`], each cell's
    /// best texture.
    pub uv_mode: UvMode,
    /// Overlay (stretch replaces the colour textures; levels tints and draws boxes).
    pub overlay: Overlay,
    /// Background loader threads (≥ 1).
    pub loader_threads: usize,
    /// Shading.
    pub frame: FrameOptions,
    /// Geomorphing of cells towards their parents (default off).
    pub geomorph: GeomorphOptions,
    /// When the camera's radial distortion is applied (default: when it has one).
    pub distortion: DistortionMode,
    /// Relief mapping (default on): on cells that have a relief map, textures are looked up
    /// where the view ray meets the DEM surface (the TIN plus the relief map) instead of
    /// where it meets the TIN, on triangles up to 75.5° (orthographic textures) or 45°
    /// (reparameterized charts) of slope. On a chart drawn with its photo texture (projected
    /// onto the TIN) only the share of each texel that is the chart's own texture moves; a
    /// chart's own share is read from its cell's orthographic texture where that has more
    /// texels per pixel.
    pub relief: bool,
}

impl Default for SceneOptions {
    fn default() -> Self {
        SceneOptions {
            sse_px: 0.5,
            budget_bytes: 512 << 20,
            uv_mode: UvMode::Photo,
            overlay: Overlay::None,
            loader_threads: 1,
            frame: FrameOptions::default(),
            geomorph: GeomorphOptions::default(),
            distortion: DistortionMode::Auto,
            relief: true,
        }
    }
}

/// What one frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Cells chosen by the LOD traversal.
    pub selected: usize,
    /// Cells drawn (after ancestor fallback).
    pub drawn: usize,
    /// Cells culled by the frustum.
    pub culled: usize,
    /// Triangles drawn (surface + skirt).
    pub triangles: u64,
    /// Selected cells drawn through a loaded ancestor because they were not loaded yet.
    pub substituted: usize,
    /// Selected cells with nothing loaded to draw.
    pub holes: usize,
    /// Loads that finished and were uploaded during this frame.
    pub uploads: usize,
    /// Wall time of the frame (upload, draw, GPU completion), milliseconds.
    pub frame_ms: f64,
    /// GPU bytes held by cached cells after the frame.
    pub gpu_bytes: u64,
    /// Cells drawn with a morph factor > 0 (geomorphing).
    pub morphed: usize,
    /// Whether the frame went through the distortion pass.
    pub distorted: bool,
    /// Size of the pinhole view rasterized for a distorted frame (0 × 0 otherwise).
    pub pinhole_size: (u32, u32),
}

/// A store with a GPU renderer, a cell cache and background loaders.
pub struct StoreRenderer {
    store: Arc<Store>,
    index: CellIndex,
    renderer: TerrainRenderer,
    cache: LruCache<GpuCell>,
    streamer: Streamer<CellData>,
    opts: SceneOptions,
    /// The loaders produce morph targets (geomorphing was on when they were started).
    morph_loaded: bool,
}

impl StoreRenderer {
    /// Opens `store_dir` and a headless GPU target of `width × height`.
    pub fn open(
        store_dir: &Path,
        width: u32,
        height: u32,
        opts: SceneOptions,
    ) -> Result<StoreRenderer> {
        Self::open_with_context(store_dir, GpuContext::new()?, width, height, opts)
    }

    /// Like [`StoreRenderer::open`] on an already opened GPU context (e.g. one whose adapter
    /// can present to a window surface).
    pub fn open_with_context(
        store_dir: &Path,
        ctx: GpuContext,
        width: u32,
        height: u32,
        opts: SceneOptions,
    ) -> Result<StoreRenderer> {
        if !(opts.sse_px.is_finite() && opts.sse_px > 0.0) {
            return Err(Error::BadOption(format!(
                "screen-space error threshold must be > 0 px, got {}",
                opts.sse_px
            )));
        }
        let store = Arc::new(Store::open(store_dir)?);
        if store.manifest.cells.iter().all(|c| c.level != 0) {
            return Err(Error::store(
                store_dir.join("manifest.json"),
                "no root (level 0) cell",
            ));
        }
        if !(opts.geomorph.band > 1.0 && opts.geomorph.band.is_finite()) {
            return Err(Error::BadOption(format!(
                "geomorph band must be a finite ratio > 1, got {}",
                opts.geomorph.band
            )));
        }
        let renderer = TerrainRenderer::new(ctx, width, height)?;
        let index = CellIndex::new(&store.manifest.cells);
        let streamer = Self::streamer(&store, &index, &opts);
        let mut opts = opts;
        if opts.overlay == Overlay::Levels {
            opts.frame.level_overlay = true;
            opts.frame.bounding_boxes = true;
        }
        Ok(StoreRenderer {
            store,
            index,
            renderer,
            cache: LruCache::new(opts.budget_bytes),
            streamer,
            morph_loaded: opts.geomorph.enabled,
            opts,
        })
    }

    /// Background loaders producing upload data for `opts.uv_mode` and `opts.overlay` (and
    /// morph targets when geomorphing).
    fn streamer(store: &Arc<Store>, index: &CellIndex, opts: &SceneOptions) -> Streamer<CellData> {
        let loader_store = Arc::clone(store);
        let index = index.clone();
        let (mode, overlay, morph) = (opts.uv_mode, opts.overlay, opts.geomorph.enabled);
        let relief = opts.relief;
        Streamer::new(opts.loader_threads, move |i| {
            let st = &loader_store;
            let rec = &st.manifest.cells[i];
            let files = active_files(rec, mode);
            let bytes = st.read_file(&files.mesh)?;
            let mesh = CellMesh::from_bytes(&bytes, &st.dir.join(&files.mesh.path))?;
            // The relief map is in the orthographic layout whatever the drawn texture's; the
            // slope limit follows the drawn texture's layout (docs/rendering.md).
            let chart_drawn = match mode {
                UvMode::Ortho => false,
                UvMode::Mixed | UvMode::Photo | UvMode::Reparam => rec.reparam.is_some(),
            };
            // The photo-enhanced texture has the layout of the active (reparam or ortho) one.
            // A chart's photo texture was projected onto the TIN (photo::LevelScene::
            // load_reliefs): relief mapping moves only the share of each texel that is the
            // chart's own texture (the base, bound beside it), the photo's colour stays.
            let mut base = None;
            let mut colour = match (&rec.photo, mode) {
                _ if overlay == Overlay::PhotoShare => photo_share_texture(st, rec, mode)?,
                (Some(p), UvMode::Photo) => {
                    if relief && chart_drawn && !overlay.replaces_texture() {
                        // (the chart's texture is the active one: read once for both)
                        let (mut texture, confidence, active) =
                            st.read_photo_texture_and_active(rec, p)?;
                        set_base_share(&mut texture, &confidence)
                            .map_err(|e| Error::store(st.dir.join(&p.confidence.path), e))?;
                        base = Some(active);
                        texture
                    } else {
                        st.read_photo_texture(rec, p)?.0
                    }
                }
                _ => st.read_png(&files.texture)?.to_rgba8(),
            };
            if overlay == Overlay::Stretch {
                colour = stretch_heatmap(rec, &mesh, colour.width().max(colour.height()));
            }
            let normal = st.read_png(&files.normal)?.to_rgb8();
            let parent = rec.key().parent().and_then(|k| index.get(k));
            let morph_data = match parent.filter(|_| morph) {
                Some(p) => {
                    let prec = &st.manifest.cells[p];
                    // The parent's mesh and texture coordinates as it is drawn in this mode.
                    let pfiles = active_files(prec, mode);
                    let pbytes = st.read_file(&pfiles.mesh)?;
                    let pmesh = CellMesh::from_bytes(&pbytes, &st.dir.join(&pfiles.mesh.path))?;
                    let puv: Vec<[f32; 2]> = (0..pmesh.positions.len())
                        .map(|k| texcoord(prec, &pmesh, k))
                        .collect();
                    let (o, po) = (rec.origin.into(), prec.origin.into());
                    let targets = morph_targets(o, &mesh, po, &pmesh, &puv, prec.skirt_depth);
                    let (pc, pn) = drawn_texels(prec, mode);
                    let (cw, pw) = (rec.extent.width(), prec.extent.width());
                    Some(MorphData {
                        targets,
                        colour_shift: mip_shift(colour.width(), cw, pc, pw),
                        normal_shift: mip_shift(normal.width(), cw, pn, pw),
                    })
                }
                None => None,
            };
            // (a photo chart without its base, e.g. under the stretch overlay: not mapped)
            let photo_chart = chart_drawn && mode == UvMode::Photo && rec.photo.is_some();
            let relief_map = if relief && (!photo_chart || base.is_some()) {
                st.read_relief_map(rec)?
            } else {
                None
            };
            let mut data = CellData::new(rec, mesh, colour, normal, mode);
            if let Some(r) = relief_map {
                let min_z = if chart_drawn {
                    crate::cells::relief::CHART_MIN_NORMAL_Z
                } else {
                    crate::cells::relief::ORTHO_MIN_NORMAL_Z
                };
                data.set_relief(r, min_z, chart_drawn, rec.extent.width());
            }
            data.base_mips = base.map(colour_mip_chain);
            // A relief-mapped chart also reads its cell's orthographic texture where that has
            // more texels per pixel (flat ground, docs/rendering.md "Photo charts by share").
            if data.relief.is_some() && chart_drawn && !overlay.replaces_texture() {
                data.ortho_mips = Some(colour_mip_chain(
                    st.read_png(&rec.files.texture)?.to_rgba8(),
                ));
            }
            data.morph = morph_data;
            Ok(data)
        })
    }

    /// Restarts the loaders and empties the cache (cells reload in the background).
    fn reload(&mut self) {
        self.streamer = Self::streamer(&self.store, &self.index, &self.opts);
        self.cache = LruCache::new(self.opts.budget_bytes);
        self.morph_loaded = self.opts.geomorph.enabled;
    }

    /// Switches geomorphing on or off. Switching off takes effect at once (cells are drawn
    /// unmorphed, with the same pipelines as a scene that never morphed); switching on reloads
    /// the cells unless they were loaded with morph targets (geomorphing was on before).
    pub fn set_geomorph(&mut self, enabled: bool) {
        self.opts.geomorph.enabled = enabled;
        if enabled && !self.morph_loaded {
            self.reload();
        }
    }

    /// Changes when the camera's radial distortion is applied (from the next frame).
    pub fn set_distortion(&mut self, mode: DistortionMode) {
        self.opts.distortion = mode;
    }

    /// Resizes the output target to `width × height` (e.g. a resized window).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        self.renderer.resize(width, height)
    }

    /// The output size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.renderer.width(), self.renderer.height())
    }

    /// Switches texture mode and overlay: drops the cached cells (they reload in the
    /// background) when the cell data changes; the level tint applies at once.
    pub fn set_mode(&mut self, uv_mode: UvMode, overlay: Overlay) {
        let reload = uv_mode != self.opts.uv_mode
            || (overlay != self.opts.overlay
                && (overlay.replaces_texture() || self.opts.overlay.replaces_texture()));
        self.opts.uv_mode = uv_mode;
        self.opts.overlay = overlay;
        self.opts.frame.level_overlay = overlay == Overlay::Levels;
        self.opts.frame.bounding_boxes = overlay == Overlay::Levels;
        if reload {
            self.reload();
        }
    }

    /// Whether any cell of the store has a photo-enhanced texture.
    pub fn has_photo(&self) -> bool {
        self.store.manifest.cells.iter().any(|c| c.photo.is_some())
    }

    /// The opened store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// The GPU in use.
    pub fn gpu(&self) -> &GpuContext {
        &self.renderer.ctx
    }

    /// GPU bytes held by cached cells.
    pub fn gpu_bytes(&self) -> u64 {
        self.cache.used_bytes()
    }

    /// A render camera for `model` with a near plane suited to its distance from the terrain
    /// (half the distance to the root bounding boxes, at least 0.25 m).
    pub fn render_camera(&self, model: &CameraModel) -> RenderCamera {
        let cells = &self.store.manifest.cells;
        let d = self
            .index
            .roots()
            .iter()
            .map(|&i| distance_to_bbox(&cells[i], model.position))
            .fold(f64::INFINITY, f64::min);
        RenderCamera::new(
            *model,
            if d.is_finite() {
                (0.5 * d).max(0.25)
            } else {
                0.25
            },
        )
    }

    fn accept(&mut self, i: usize, data: Result<CellData>) -> Result<()> {
        let rec = &self.store.manifest.cells[i];
        let cell = self.renderer.upload(rec, &data?)?;
        let bytes = cell.bytes;
        drop(self.cache.insert(i, cell, bytes));
        Ok(())
    }

    /// The pinhole view a frame of `model` is rasterized through when its distortion applies
    /// (see [`DistortionMode`]), else `None`.
    pub fn distorted_view(&self, model: &CameraModel) -> Result<Option<DistortedView>> {
        if !self.opts.distortion.applies_to(model) {
            return Ok(None);
        }
        let max = self.renderer.ctx.device.limits().max_texture_dimension_2d;
        DistortedView::new(model, max).map(Some)
    }

    /// Morph factor of cell `i` in a frame seen by `cam` (0 when not geomorphing or for roots).
    fn morph_of(&self, i: usize, cam: &RenderCamera) -> f32 {
        let cells = &self.store.manifest.cells;
        let rec = &cells[i];
        let g = &self.opts.geomorph;
        let Some(p) = rec
            .key()
            .parent()
            .and_then(|k| self.index.get(k))
            .filter(|_| g.enabled)
        else {
            return 0.0;
        };
        let thr = self.opts.sse_px;
        let parent = screen_space_error(&cells[p], cam) / thr;
        let own = self
            .index
            .children(rec.key())
            .next()
            .map(|_| screen_space_error(rec, cam) / thr);
        morph_factor(parent, own, g.band)
    }

    /// Renders one frame from `model` (whose size must be the target's). With `complete`,
    /// waits until every selected cell is loaded (for stills); otherwise never waits for the
    /// disk: missing cells are requested and drawn through their nearest loaded ancestor.
    /// A camera with radial distortion is rasterized through its [`DistortedView`] and
    /// resampled (unless the scene's [`DistortionMode`] is `Off`); LOD and culling then use
    /// the pinhole view (at least as dense as the output everywhere).
    pub fn frame(&mut self, model: &CameraModel, complete: bool) -> Result<FrameReport> {
        let start = Instant::now();
        let distorted = self.distorted_view(model)?;
        let cam = self.render_camera(distorted.as_ref().map_or(model, |d| &d.pinhole));
        let store = Arc::clone(&self.store);
        let cells = &store.manifest.cells;
        // A morphing cell's vertices move to the parent's surface, at most the parent's
        // geometric error away (its vertices are DEM samples); its skirt reaches the parent's
        // skirt depth below that. Cells that do not morph keep their boxes.
        let index = &self.index;
        let sel = select_cells_with_margin(cells, index, &cam, self.opts.sse_px, |i| {
            match cells[i].key().parent().and_then(|k| index.get(k)) {
                Some(p) if self.morph_of(i, &cam) > 0.0 => {
                    let e = geometric_error(&cells[p]);
                    (
                        e,
                        e + (cells[p].skirt_depth - cells[i].skirt_depth).max(0.0),
                    )
                }
                _ => (0.0, 0.0),
            }
        });
        self.cache.begin_frame();
        for &i in &sel.cells {
            self.cache.get(i);
        }
        let mut report = FrameReport {
            selected: sel.cells.len(),
            culled: sel.culled,
            ..Default::default()
        };
        for (i, data) in self.streamer.poll() {
            self.accept(i, data)?;
            report.uploads += 1;
        }
        for &r in self.index.roots() {
            if !self.cache.contains(r) {
                self.streamer.request(r);
            }
        }
        let eye = model.position;
        let mut missing: Vec<usize> = sel
            .cells
            .iter()
            .copied()
            .filter(|&i| !self.cache.contains(i))
            .collect();
        missing.sort_by(|&a, &b| {
            distance_to_bbox(&cells[a], eye)
                .total_cmp(&distance_to_bbox(&cells[b], eye))
                .then(a.cmp(&b))
        });
        for &i in &missing {
            self.streamer.request(i);
        }
        if complete {
            while missing.iter().any(|&i| !self.cache.contains(i)) {
                let Some((i, data)) = self.streamer.wait_one() else {
                    break;
                };
                self.accept(i, data)?;
                report.uploads += 1;
            }
        }
        let dl = resolve_draw_list(&sel.cells, cells, &self.index, |i| self.cache.contains(i));
        for &i in &dl.draw {
            self.cache.get(i);
        }
        let morphs: Vec<f32> = dl.draw.iter().map(|&i| self.morph_of(i, &cam)).collect();
        // Parents of morphing cells lend their textures: keep them (or have them loaded).
        let parent_of = |i: usize| cells[i].key().parent().and_then(|k| self.index.get(k));
        let parents: Vec<Option<usize>> = dl
            .draw
            .iter()
            .zip(&morphs)
            .map(|(&i, &m)| parent_of(i).filter(|_| m > 0.0))
            .collect();
        for &p in parents.iter().flatten() {
            if self.cache.get(p).is_none() {
                self.streamer.request(p);
            }
        }
        let cache = &self.cache;
        let draw: Vec<CellDraw> = dl
            .draw
            .iter()
            .zip(morphs)
            .zip(parents)
            .filter_map(|((&i, morph), p)| {
                let cell: &GpuCell = cache.peek(i)?;
                Some(CellDraw {
                    cell,
                    morph,
                    parent: p.and_then(|p| cache.peek(p)),
                })
            })
            .collect();
        report.drawn = draw.len();
        report.morphed = draw
            .iter()
            .filter(|d| d.morph > 0.0 && d.cell.can_morph())
            .count();
        report.substituted = dl.substituted;
        report.holes = dl.holes;
        report.distorted = distorted.is_some();
        report.pinhole_size = distorted.map_or((0, 0), |d| (d.pinhole.width, d.pinhole.height));
        report.triangles =
            self.renderer
                .render(&cam, &draw, &self.opts.frame, distorted.as_ref())?;
        report.gpu_bytes = self.cache.used_bytes();
        report.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(report)
    }

    /// The last frame's pixels (sRGB RGBA8, row 0 at the top).
    pub fn read_rgba(&self) -> Result<image::RgbaImage> {
        self.renderer.read_rgba()
    }

    /// The last frame's reverse-Z depth buffer (see [`TerrainRenderer::read_depth`]).
    pub fn read_depth(&self) -> Result<Vec<f32>> {
        self.renderer.read_depth()
    }

    /// Current options.
    pub fn options(&self) -> &SceneOptions {
        &self.opts
    }

    /// Changes the screen-space error threshold (pixels, finite and > 0).
    pub fn set_sse(&mut self, sse_px: f64) -> Result<()> {
        if !(sse_px.is_finite() && sse_px > 0.0) {
            return Err(Error::BadOption(format!(
                "screen-space error threshold must be > 0 px, got {sse_px}"
            )));
        }
        self.opts.sse_px = sse_px;
        Ok(())
    }

    /// Changes the shading options of the following frames.
    pub fn set_frame_options(&mut self, frame: FrameOptions) {
        self.opts.frame = frame;
    }

    /// World position of the centre of the store's root bounding box (for default views).
    pub fn centre(&self) -> DVec3 {
        let cells = &self.store.manifest.cells;
        let r = &cells[self.index.roots()[0]];
        (DVec3::from(r.bbox_min) + DVec3::from(r.bbox_max)) / 2.0
    }
}

/// The [`Overlay::PhotoShare`] texture of a cell drawn in `mode`: its photo share where it
/// has a photo texture in the drawn texture's layout (every mode but `Ortho`, and `Ortho` on
/// cells that were not reparameterized), else [`NO_PHOTO_COLOUR`] at the drawn size.
fn photo_share_texture(st: &Store, rec: &CellRecord, mode: UvMode) -> Result<image::RgbaImage> {
    let same_layout = mode != UvMode::Ortho || rec.reparam.is_none();
    match &rec.photo {
        Some(p) if same_layout => Ok(share_map(&st.read_photo_confidence(p)?)),
        _ => {
            let n = drawn_texels(rec, mode).1;
            Ok(image::RgbaImage::from_pixel(
                n,
                n,
                image::Rgba(NO_PHOTO_COLOUR),
            ))
        }
    }
}

/// The files a cell is drawn from in `mode`: its reparameterized variant where it has one,
/// unless the baseline orthographic rendering is asked for.
fn active_files(rec: &CellRecord, mode: UvMode) -> &crate::store::CellFiles {
    match (&rec.reparam, mode) {
        (Some(r), UvMode::Mixed | UvMode::Reparam | UvMode::Photo) => &r.files,
        _ => &rec.files,
    }
}

/// Side lengths in texels of the colour texture and normal map a cell is drawn with in `mode`.
fn drawn_texels(rec: &CellRecord, mode: UvMode) -> (u32, u32) {
    let base = match (&rec.reparam, mode) {
        (Some(r), UvMode::Mixed | UvMode::Reparam | UvMode::Photo) => r.texels,
        _ => rec.texels,
    };
    let colour = match (&rec.photo, mode) {
        (Some(p), UvMode::Photo) => p.texels,
        _ => base,
    };
    (colour, base)
}
