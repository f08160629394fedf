//! What the store shows from a camera, as samples to reproject: one ray per pixel of a
//! (scaled) image grid cast against the store's terrain, each hit kept as its world point
//! with a label (the colour of the cell's active texture, the surface's steepness and its
//! distance class), each ray above the terrain's reach kept as a sky direction.

use glam::{DVec3, Vec3};
use image::RgbaImage;
use rayon::prelude::*;

use crate::camera::CameraModel;
use crate::error::Result;
use crate::raycast::LevelScene;
use crate::store::Store;

/// Grid stride of the samples [`LabelledTerrain::sample`] keeps away from the silhouettes when
/// it keeps a band around them. The band gives the score its sharp peak; these sparse
/// samples of the regions' insides tie the score to the view as a whole, so that a band
/// made mostly of where the store ends (a photo that sees far beyond the store, as at
/// Engabreen) cannot line up with a wrong edge (docs/registration.md).
pub const INNER_STRIDE: usize = 3;

/// Number of texture-grey classes of a terrain sample's label.
pub const GREY_CLASSES: u8 = 10;
/// Label of a sky sample (terrain labels are `1..LABELS`).
pub const SKY: u8 = 0;
/// Number of labels: sky, then grey × steep (2) × distance (2) × source (2: the store's
/// texture, or a label photo's pixels, [`LabelledTerrain::set_label_photos`]).
pub const LABELS: usize = 1 + GREY_CLASSES as usize * 8;

/// What one sample is: a terrain point (world metres) or a sky direction (unit, world).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleAt {
    /// A point of the terrain (reprojects with position and rotation).
    Point(DVec3),
    /// A direction to the sky (reprojects with the rotation only).
    Sky(DVec3),
}

/// One sample of a view: where it is and its label (see [`LABELS`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Where the sample is.
    pub at: SampleAt,
    /// Its label: [`SKY`], or `1 + grey + GREY_CLASSES · (2 · far + steep + 4 · photo)`
    /// (`photo`: the grey came from a label photo; greys are classed per source).
    pub label: u8,
}

impl Sample {
    /// Whether the sample's grey came from a label photo ([`LabelledTerrain::set_label_photos`]).
    pub fn photo_labelled(&self) -> bool {
        self.label != SKY && (self.label - 1) / GREY_CLASSES >= 4
    }
}

/// Share (0..1) of the terrain samples (not sky) of `samples` whose grey came from a label
/// photo; 0 without terrain samples.
pub fn photo_label_share(samples: &[Sample]) -> f64 {
    let terrain = samples.iter().filter(|s| s.label != SKY).count();
    let photo = samples.iter().filter(|s| s.photo_labelled()).count();
    photo as f64 / terrain.max(1) as f64
}

/// Where a ray ends ([`LabelledTerrain::classify`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RayEnd {
    /// On the terrain: the point (world metres) and its distance from the ray's origin.
    Terrain(DVec3, f64),
    /// In the sky.
    Sky,
}

/// Which texture of a cell gives a terrain sample its grey ([`LabelledTerrain::with_labels`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LabelTexture {
    /// The active parameterization's texture (reparameterized, else ortho); photo textures
    /// are never used, so an earlier projection with a wrong pose cannot pull the fit.
    #[default]
    Active,
    /// The photo-enhanced texture where `cliffmap project` wrote one, else the active one:
    /// sharper labels where photos with trusted cameras (from `fit-camera`, or registered
    /// earlier) already cover what this photo sees.
    Best,
}

impl LabelTexture {
    /// The name `cliffmap register --textures` and its report use: "active" or "best".
    pub fn name(self) -> &'static str {
        match self {
            LabelTexture::Active => "active",
            LabelTexture::Best => "best",
        }
    }
}

/// A cell's label texture and the factor from active-texture texels to its texels.
type LabelImage = std::sync::Arc<(RgbaImage, f32)>;

/// The store's finest level as a ray-castable scene with the label textures the rays hit
/// (loaded on demand) and the terrain's highest point.
pub struct LabelledTerrain<'a> {
    store: &'a Store,
    scene: LevelScene,
    labels: LabelTexture,
    textures: std::sync::Mutex<Vec<Option<LabelImage>>>,
    label_photos: Vec<LabelPhoto>,
    top_z: f64,
    lo: [f64; 2],
    hi: [f64; 2],
}

impl<'a> LabelledTerrain<'a> {
    /// The finest level of `store`, in an f32 frame centred on `near` (a camera position),
    /// labelled by the active textures ([`LabelTexture::Active`]).
    pub fn new(store: &'a Store, near: DVec3) -> Result<LabelledTerrain<'a>> {
        Self::with_labels(store, near, LabelTexture::Active)
    }

    /// [`LabelledTerrain::with_labels`] with the labels `opts` asks for.
    pub fn for_options(
        store: &'a Store,
        near: DVec3,
        opts: &super::TerrainOptions,
    ) -> Result<LabelledTerrain<'a>> {
        Self::with_labels(store, near, opts.labels)
    }

    /// [`LabelledTerrain::new`] with the samples' greys taken from `labels`.
    pub fn with_labels(
        store: &'a Store,
        near: DVec3,
        labels: LabelTexture,
    ) -> Result<LabelledTerrain<'a>> {
        let level = store.manifest.quadtree.levels.saturating_sub(1);
        let scene = LevelScene::from_store(
            store,
            level,
            near,
            crate::raycast::RayAccel::Bvh(crate::raycast::BvhQuality::default()),
        )?;
        let (mut lo, mut hi, mut top_z) = (
            [f64::INFINITY; 2],
            [f64::NEG_INFINITY; 2],
            f64::NEG_INFINITY,
        );
        for c in &scene.cells {
            for p in &c.positions {
                let w = c.origin + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                lo = [lo[0].min(w.x), lo[1].min(w.y)];
                hi = [hi[0].max(w.x), hi[1].max(w.y)];
                top_z = top_z.max(w.z);
            }
        }
        let n = scene.cells.len();
        Ok(LabelledTerrain {
            store,
            scene,
            labels,
            textures: std::sync::Mutex::new(vec![None; n]),
            label_photos: Vec::new(),
            top_z,
            lo,
            hi,
        })
    }

    /// Photos with trusted cameras whose pixels label the terrain samples they see (instead
    /// of the cells' textures): per sample, of the photos that show its point unoccluded,
    /// the one that resolves it finest (smallest distance / focal length). Their greys are
    /// classed apart from the textures' (a label's source is part of it). Replaces any
    /// earlier set; a photo whose image size is not its camera's is ignored.
    pub fn set_label_photos(&mut self, photos: &[(CameraModel, &image::RgbImage)]) {
        self.label_photos = photos
            .iter()
            .filter(|(c, img)| (c.width, c.height) == img.dimensions())
            .map(|(c, img)| LabelPhoto::new(*c, img))
            .collect();
    }

    /// Share (0..1) of the terrain samples of `cam`'s view (one per pixel) that the label
    /// photos label; 0 without label photos or terrain in view.
    pub fn photo_label_share(&self, cam: &CameraModel) -> Result<f64> {
        if self.label_photos.is_empty() {
            return Ok(0.0);
        }
        Ok(photo_label_share(&self.sample(cam, 1.0, 0.0, None)?))
    }

    /// Whether label photos are set ([`LabelledTerrain::set_label_photos`]).
    pub fn has_label_photos(&self) -> bool {
        !self.label_photos.is_empty()
    }

    /// Grey (0..1) of the label photo that shows `point` finest, unoccluded (its ray meets
    /// the terrain within 0.1 m + 0.2 % of the distance of `point`), if any.
    fn photo_grey(&self, bvh: &crate::raycast::TriangleBvh, point: DVec3) -> Option<f32> {
        let mut best: Option<(f64, f32)> = None;
        for lp in &self.label_photos {
            let d = point - lp.camera.position;
            let dist = d.length();
            let res = dist / lp.camera.fx;
            if best.is_some_and(|b| b.0 <= res) || dist <= 0.0 {
                continue;
            }
            let Some(px) = lp.camera.project(point) else {
                continue;
            };
            let Some(g) = lp.at(px[0], px[1]) else {
                continue;
            };
            let origin = (lp.camera.position - self.scene.frame_origin).as_vec3();
            let dir = (d / dist).as_vec3();
            let seen = bvh
                .nearest(origin, dir, 0.05, f32::INFINITY)
                .is_some_and(|h| (h.t as f64 - dist).abs() <= 0.1 + 0.002 * dist);
            if seen {
                best = Some((res, g));
            }
        }
        best.map(|b| b.1)
    }

    /// Samples of the view of `cam` at the centres of a `step`-pixel grid inside the image
    /// inset by `margin` (a fraction of each side): terrain hits labelled by their texture
    /// grey (quantiles of the view's own greys), steepness (normal more than 45° from up)
    /// and distance (beyond the view's median distance); misses whose ray rises above the
    /// terrain's highest point before it leaves the terrain's extent as sky; other misses
    /// (rays that leave the store's extent below its top, where the land goes on unseen)
    /// are dropped. With `band = Some(w)` the samples within `w` grid steps of a layer
    /// boundary (sky against terrain, dropped against kept, or a distance jump of more than
    /// 25 %: the silhouettes) are kept, and of the others one in `INNER_STRIDE`² (every
    /// `INNER_STRIDE`-th grid row and column). Deterministic.
    pub fn sample(
        &self,
        cam: &CameraModel,
        step: f64,
        margin: f64,
        band: Option<usize>,
    ) -> Result<Vec<Sample>> {
        let (w, h) = (cam.width as f64, cam.height as f64);
        let (u0, v0) = (margin * w, margin * h);
        let grid = SampleGrid {
            u0,
            v0,
            nu: ((w - 2.0 * u0) / step).floor() as usize,
            nv: ((h - 2.0 * v0) / step).floor() as usize,
            step,
        };
        let Some(bvh) = self.scene.bvh() else {
            return Ok(Vec::new());
        };
        let raw = self.cast_grid(cam, &grid, bvh);
        let mut out_at = self.label_hits(cam, &raw)?;
        let mut dists: Vec<f32> = out_at
            .iter()
            .flatten()
            .filter_map(|a| a.as_ref().ok().map(|h| h.dist))
            .collect();
        dists.sort_unstable_by(f32::total_cmp);
        let median = dists.get(dists.len() / 2).copied().unwrap_or(0.0);
        let keep = match band {
            None => vec![true; out_at.len()],
            Some(wb) => band_keep(&out_at, grid.nu, grid.nv, wb),
        };
        // Greys from the label photos, where one shows the point: only for the samples
        // kept (each costs a ray to test the point's visibility from every label photo).
        if !self.label_photos.is_empty() {
            let greys: Vec<Option<f32>> = out_at
                .par_iter()
                .zip(&keep)
                .map(|(a, &k)| match a {
                    Some(Ok(h)) if k => self.photo_grey(bvh, h.point),
                    _ => None,
                })
                .collect();
            for (a, g) in out_at.iter_mut().zip(greys) {
                if let (Some(Ok(h)), Some(g)) = (a, g) {
                    h.grey = g;
                    h.photo = true;
                }
            }
        }
        // grey class boundaries per source (texture, label photo): quantiles of the view's
        // own greys; with label photos and a band, over the uniform one-in-`INNER_STRIDE`²
        // grid of samples (kept, so their source is known; an unbiased subset of the view)
        let nu = grid.nu;
        let uniform = |i: usize| {
            (i / nu).is_multiple_of(INNER_STRIDE) && (i % nu).is_multiple_of(INNER_STRIDE)
        };
        let quantile_set = |i: usize| self.label_photos.is_empty() || band.is_none() || uniform(i);
        let cuts = [false, true].map(|photo| grey_cuts(&out_at, photo, &quantile_set));
        Ok(out_at
            .into_iter()
            .zip(keep)
            .filter_map(|(a, k)| if k { a } else { None })
            .map(|a| labelled(a, &cuts, median))
            .collect())
    }

    /// One ray per grid cell (jittered inside it by a fixed hash of its index: samples on
    /// the photo's pixel centres would make the score favour whole-pixel shifts): its
    /// direction and nearest hit, `None` where the camera has no ray.
    #[allow(clippy::type_complexity)]
    fn cast_grid(
        &self,
        cam: &CameraModel,
        grid: &SampleGrid,
        bvh: &crate::raycast::TriangleBvh,
    ) -> Vec<Option<(DVec3, Option<crate::raycast::TriHit>)>> {
        let caster = cam.ray_caster();
        let origin = (cam.position - self.scene.frame_origin).as_vec3();
        let SampleGrid {
            u0,
            v0,
            nu,
            nv,
            step,
        } = *grid;
        (0..nu * nv)
            .into_par_iter()
            .map(|i| {
                let (ju, jv) = jitter(i as u64);
                let u = u0 + ((i % nu) as f64 + 0.5 + ju) * step - 0.5;
                let v = v0 + ((i / nu) as f64 + 0.5 + jv) * step - 0.5;
                let dir = caster.ray(u, v)?;
                Some((dir, bvh.nearest(origin, dir.as_vec3(), 0.05, f32::INFINITY)))
            })
            .collect()
    }

    /// Per ray: a terrain hit with its texture grey, steepness and distance; the ray's
    /// direction where it is sky; `None` where it is dropped (no ray, or it leaves the
    /// store below its top).
    #[allow(clippy::type_complexity)]
    fn label_hits(
        &self,
        cam: &CameraModel,
        raw: &[Option<(DVec3, Option<crate::raycast::TriHit>)>],
    ) -> Result<Vec<Option<std::result::Result<ViewHit, DVec3>>>> {
        // Textures of the cells hit.
        let mut need: Vec<usize> = raw
            .iter()
            .flatten()
            .filter_map(|(_, h)| h.map(|h| self.scene.cell_of(h.triangle) as usize))
            .collect();
        need.sort_unstable();
        need.dedup();
        self.load_textures(&need)?;
        let textures = self
            .textures
            .lock()
            .map_err(|_| crate::error::Error::BadOption("texture cache poisoned".into()))?
            .clone();
        let mut out_at = Vec::with_capacity(raw.len());
        for r in raw {
            let Some((dir, hit)) = r else {
                out_at.push(None);
                continue;
            };
            match hit {
                Some(hh) => {
                    let point = cam.position + *dir * hh.t as f64;
                    let plane = self.scene.plane(hh.triangle);
                    let steep = plane[2].abs() < std::f32::consts::FRAC_1_SQRT_2;
                    let tex = self.scene.tri_texcoords(hh.triangle);
                    let p = [0, 1].map(|k| {
                        hh.bary[0] * tex[0][k] + hh.bary[1] * tex[1][k] + hh.bary[2] * tex[2][k]
                    });
                    let grey = textures[self.scene.cell_of(hh.triangle) as usize]
                        .as_deref()
                        .map_or(0.5, |t| grey_at(&t.0, p.map(|v| v * t.1)));
                    out_at.push(Some(Ok(ViewHit {
                        point,
                        grey,
                        steep,
                        dist: hh.t,
                        photo: false,
                    })));
                }
                None if self.rises_above(cam.position, *dir) => out_at.push(Some(Err(*dir))),
                None => out_at.push(None),
            }
        }
        Ok(out_at)
    }

    /// Whether a ray from `from` along `dir` (no terrain hit) is sky: it climbs above the
    /// terrain's top before leaving the terrain's x-y extent (else it may meet land beyond
    /// the store).
    fn rises_above(&self, from: DVec3, dir: DVec3) -> bool {
        if dir.z <= 0.0 {
            return false;
        }
        let t_top = ((self.top_z - from.z) / dir.z).max(0.0);
        let mut t_exit = f64::INFINITY;
        for k in 0..2 {
            let (o, d) = (from[k], dir[k]);
            if d > 1e-12 {
                t_exit = t_exit.min((self.hi[k] - o) / d);
            } else if d < -1e-12 {
                t_exit = t_exit.min((self.lo[k] - o) / d);
            }
        }
        t_top <= t_exit.max(0.0)
    }

    fn load_textures(&self, cells: &[usize]) -> Result<()> {
        let missing: Vec<usize> = {
            let t = self
                .textures
                .lock()
                .map_err(|_| crate::error::Error::BadOption("texture cache poisoned".into()))?;
            cells.iter().copied().filter(|&c| t[c].is_none()).collect()
        };
        let loaded: Vec<(usize, (RgbaImage, f32))> = missing
            .par_iter()
            .map(|&c| {
                let rec = &self.store.manifest.cells[self.scene.cells[c].cell as usize];
                match (&rec.photo, self.labels) {
                    (Some(photo), LabelTexture::Best) => {
                        let (t, _) = self.store.read_photo_texture(rec, photo)?;
                        let scale =
                            t.width() as f32 / crate::store::active_texels(rec).max(1) as f32;
                        Ok((c, (t, scale)))
                    }
                    _ => self.store.read_active_texture(rec).map(|t| (c, (t, 1.0))),
                }
            })
            .collect::<Result<_>>()?;
        let mut t = self
            .textures
            .lock()
            .map_err(|_| crate::error::Error::BadOption("texture cache poisoned".into()))?;
        for (c, img) in loaded {
            t[c] = Some(std::sync::Arc::new(img));
        }
        Ok(())
    }

    /// What the ray from `from` along the unit `dir` (world) meets: the terrain (point and
    /// distance), the sky (`LabelledTerrain::rises_above`), or nothing known (`None`: it
    /// leaves the store's extent below its top).
    pub fn classify(&self, from: DVec3, dir: DVec3) -> Option<RayEnd> {
        match self.hit(from, dir) {
            Some(p) => Some(RayEnd::Terrain(p, (p - from).length())),
            None if self.rises_above(from, dir) => Some(RayEnd::Sky),
            None => None,
        }
    }

    /// The terrain's highest point (world metres).
    pub fn top_z(&self) -> f64 {
        self.top_z
    }

    /// The first terrain hit of the ray from `from` along the unit `dir` (world), if any.
    pub fn hit(&self, from: DVec3, dir: DVec3) -> Option<DVec3> {
        let origin: Vec3 = (from - self.scene.frame_origin).as_vec3();
        let h = self
            .scene
            .bvh()?
            .nearest(origin, dir.as_vec3(), 0.05, f32::INFINITY)?;
        Some(from + dir * h.t as f64)
    }
}

/// Luma (Rec. 709 weights on the sRGB values, 0..1) of the texel containing position `p`
/// (texel units, clamped to the texture).
fn grey_at(t: &RgbaImage, p: [f32; 2]) -> f32 {
    let x = (p[0].floor().max(0.0) as u32).min(t.width().saturating_sub(1));
    let y = (p[1].floor().max(0.0) as u32).min(t.height().saturating_sub(1));
    let c = t.get_pixel(x, y).0;
    (0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32) / 255.0
}

/// `mask` (row-major `nu × nv`) dilated by a `w`-step square (rows, then columns).
fn dilate(mask: &[bool], nu: usize, nv: usize, w: usize) -> Vec<bool> {
    let mut rows = vec![false; mask.len()];
    for r in 0..nv {
        dilate_line(mask, &mut rows, r * nu, 1, nu, w);
    }
    let mut out = vec![false; mask.len()];
    for c in 0..nu {
        dilate_line(&rows, &mut out, c, nu, nv, w);
    }
    out
}

/// One line of `n` cells at `start + k·stride` of `src` dilated by `w` into `dst`.
fn dilate_line(src: &[bool], dst: &mut [bool], start: usize, stride: usize, n: usize, w: usize) {
    let mut last_set: Option<usize> = None;
    let mut next_set = vec![usize::MAX; n];
    let mut nx = usize::MAX;
    for k in (0..n).rev() {
        if src[start + k * stride] {
            nx = k;
        }
        next_set[k] = nx;
    }
    for k in 0..n {
        if src[start + k * stride] {
            last_set = Some(k);
        }
        dst[start + k * stride] = last_set.is_some_and(|l| k - l <= w)
            || (next_set[k] != usize::MAX && next_set[k] - k <= w);
    }
}

/// Two numbers in [-0.5, 0.5) from an index (SplitMix64), the same on every run.
fn jitter(i: u64) -> (f64, f64) {
    let mut z = i
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(0x2545_F491_4F6C_DD1D);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (
        (z >> 40) as f64 / (1u64 << 24) as f64 - 0.5,
        (z & 0xFF_FFFF) as f64 / (1u64 << 24) as f64 - 0.5,
    )
}

/// A photo with a trusted camera as grey levels for labelling terrain samples.
struct LabelPhoto {
    camera: CameraModel,
    luma: Vec<f32>,
}

impl LabelPhoto {
    fn new(camera: CameraModel, img: &image::RgbImage) -> LabelPhoto {
        let luma = img
            .pixels()
            .map(|p| (0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32) / 255.0)
            .collect();
        LabelPhoto { camera, luma }
    }

    /// Bilinear grey at pixel position (u, v) (pixel-centre convention), `None` outside.
    fn at(&self, u: f64, v: f64) -> Option<f32> {
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        if !(u >= 0.0 && v >= 0.0 && u <= (w - 1) as f64 && v <= (h - 1) as f64) {
            return None;
        }
        let (x0, y0) = (u.floor() as usize, v.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = ((u - x0 as f64) as f32, (v - y0 as f64) as f32);
        let l = &self.luma;
        let top = l[y0 * w + x0] * (1.0 - fx) + l[y0 * w + x1] * fx;
        let bot = l[y1 * w + x0] * (1.0 - fx) + l[y1 * w + x1] * fx;
        Some(top * (1.0 - fy) + bot * fy)
    }
}

/// The grid of a view's samples: `nu × nv` cells of `step` pixels from `(u0, v0)`.
#[derive(Clone, Copy)]
struct SampleGrid {
    u0: f64,
    v0: f64,
    nu: usize,
    nv: usize,
    step: f64,
}

/// A terrain hit of a view sample: where, its grey (texture or label photo), whether the
/// surface is steep, the ray's length and whether a label photo gave the grey.
struct ViewHit {
    point: DVec3,
    grey: f32,
    steep: bool,
    dist: f32,
    photo: bool,
}

/// Which samples a band of `wb` grid steps keeps: those within it of a layer boundary (sky
/// against terrain, dropped against kept, or a distance jump of more than 25 %) and one in
/// `INNER_STRIDE`² of the others.
fn band_keep(
    out_at: &[Option<std::result::Result<ViewHit, DVec3>>],
    nu: usize,
    nv: usize,
    wb: usize,
) -> Vec<bool> {
    // Layers: -1 dropped, 0 sky, else the hit's distance.
    let layer = |i: usize| match &out_at[i] {
        None => -1.0f32,
        Some(Err(_)) => 0.0,
        Some(Ok(h)) => h.dist,
    };
    let differs = |a: f32, b: f32| {
        if a <= 0.0 || b <= 0.0 {
            a != b
        } else {
            a.max(b) > 1.25 * a.min(b)
        }
    };
    let mut edge = vec![false; out_at.len()];
    for r in 0..nv {
        for c in 0..nu {
            let i = r * nu + c;
            if c + 1 < nu && differs(layer(i), layer(i + 1)) {
                edge[i] = true;
                edge[i + 1] = true;
            }
            if r + 1 < nv && differs(layer(i), layer(i + nu)) {
                edge[i] = true;
                edge[i + nu] = true;
            }
        }
    }
    let mut keep = dilate(&edge, nu, nv, wb);
    for r in (0..nv).step_by(INNER_STRIDE) {
        for c in (0..nu).step_by(INNER_STRIDE) {
            keep[r * nu + c] = true;
        }
    }
    keep
}

/// The grey class boundaries of the hits whose grey came from a label photo (`photo`) or
/// from the texture: quantiles over the samples `in_set` selects.
fn grey_cuts(
    out_at: &[Option<std::result::Result<ViewHit, DVec3>>],
    photo: bool,
    in_set: &dyn Fn(usize) -> bool,
) -> Vec<f32> {
    let mut greys: Vec<f32> = out_at
        .iter()
        .enumerate()
        .filter(|(i, _)| in_set(*i))
        .filter_map(|(_, a)| a.as_ref()?.as_ref().ok())
        .filter(|h| h.photo == photo)
        .map(|h| h.grey)
        .collect();
    greys.sort_unstable_by(f32::total_cmp);
    (1..GREY_CLASSES as usize)
        .map(|k| {
            greys
                .get(k * greys.len() / GREY_CLASSES as usize)
                .copied()
                .unwrap_or(0.5)
        })
        .collect()
}

/// A kept sample with its label: sky, or a terrain class (grey class from `cuts`, source,
/// beyond the `median` distance, steep).
fn labelled(a: std::result::Result<ViewHit, DVec3>, cuts: &[Vec<f32>; 2], median: f32) -> Sample {
    match a {
        Ok(hit) => {
            let g = cuts[usize::from(hit.photo)]
                .iter()
                .filter(|&&c| hit.grey > c)
                .count() as u8;
            let class =
                4 * u8::from(hit.photo) + 2 * u8::from(hit.dist > median) + u8::from(hit.steep);
            Sample {
                at: SampleAt::Point(hit.point),
                label: 1 + g + GREY_CLASSES * class,
            }
        }
        Err(dir) => Sample {
            at: SampleAt::Sky(dir),
            label: SKY,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_marks_exactly_the_square_around_each_set_cell() {
        let (nu, nv) = (9, 7);
        let mut m = vec![false; nu * nv];
        m[3 * nu + 4] = true;
        m[0] = true;
        let d = dilate(&m, nu, nv, 2);
        for r in 0..nv {
            for c in 0..nu {
                let want = (r.abs_diff(3) <= 2 && c.abs_diff(4) <= 2) || (r <= 2 && c <= 2);
                assert_eq!(d[r * nu + c], want, "({c}, {r})");
            }
        }
    }

    #[test]
    fn jitter_stays_inside_the_cell_and_repeats() {
        for i in 0..1000 {
            let (a, b) = jitter(i);
            assert!((-0.5..0.5).contains(&a) && (-0.5..0.5).contains(&b));
            assert_eq!(jitter(i), (a, b));
        }
    }
}
