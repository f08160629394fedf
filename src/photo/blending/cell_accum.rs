//! All photos' contributions to one cell texture ([`CellAccum`]: the sharpest photos win,
//! weighted or best view, [`BlendMode`]) and what the resolution rule knows of the cell
//! ([`CellContext`]). A cell's first photo hands over its [`PhotoAccum`]'s memory; later
//! photos are merged texel by texel, in photo order (docs/projection.md, "Several photos").

use crate::photo::splatting::accumulate::PhotoAccum;
use crate::photo::splatting::confidence::ConfidenceParams;
use crate::photo::splatting::texel_tiles::{TexelSums, TexelTiles};

/// The photo index of a record's label (1 + the index, 0 for none; see [`CellAccum`]).
#[inline]
fn label_photo(label: f32) -> Option<u16> {
    (label >= 1.0).then_some((label - 1.0) as u16)
}

/// How several photos' colours combine in a texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BlendMode {
    /// Average of the photos' colours weighted by coverage confidence × resolution^−γ
    /// ([`ConfidenceParams::sharpness_power`]): the sharpest photo dominates, photos of
    /// similar resolution are averaged.
    #[default]
    Confidence,
    /// The colour of the photo with the highest such weight (first photo on ties).
    Best,
}

impl BlendMode {
    /// The name stored in the manifest: "blend" or "best".
    pub fn name(self) -> &'static str {
        match self {
            BlendMode::Confidence => "blend",
            BlendMode::Best => "best",
        }
    }
}

/// The least factor of a photo's selection weight on texels next to its occlusion edges
/// (occlusion weight 0): another photo that sees such a texel clear of its own edges wins
/// unless it resolves the surface about 5.6× more coarsely (`1000^(1/4)`, γ = 4).
const EDGE_FLOOR: f32 = 1e-3;

/// `x^−p` for `x > 0`; by multiplications when `p` is a small whole number (the default 4).
#[inline]
fn inverse_power(x: f32, p: f32) -> f32 {
    if p == 4.0 {
        let q = 1.0 / (x * x);
        q * q
    } else if p.fract() == 0.0 && (0.0..=16.0).contains(&p) {
        (1.0 / x).powi(p as i32)
    } else {
        x.powf(-p)
    }
}

/// Surface slopes whose cosine is below this count as this in [`CellContext`] (an ortho
/// pixel smeared over ~20 ortho pixels of wall height).
pub const MIN_COS_SLOPE: f32 = 0.05;

/// What the resolution rule needs to know about one cell (docs/projection.md, "Blending").
#[derive(Clone, Debug, PartialEq)]
pub struct CellContext {
    /// Side of the cell's existing (active) texture and normal map, texels.
    pub base_texels: u32,
    /// Per existing texel (row-major), the cosine of the surface slope from the normal map
    /// (1 = flat, 0 = vertical).
    pub cos_slope: Vec<f32>,
    /// The cell TIN's vertical error bound `ε` (metres): its surface lies within `ε` of the
    /// DEM vertically, so within `ε·cos θ` along the surface normal.
    pub max_error: f32,
    /// Ground sample distance the existing texture resolves (metres): the larger of the
    /// ortho's pixel spacing and the existing texture's texel size on the ground.
    pub existing_ground: f32,
    /// The existing texture's texel size on the ground (metres; of the orthographic texture,
    /// which reparameterized ones are resampled from).
    pub texel_ground: f32,
}

impl CellContext {
    /// A context for a flat cell (every cosine 1) of `base_texels` side.
    pub fn flat(base_texels: u32, max_error: f32, existing_ground: f32) -> CellContext {
        let n = base_texels as usize * base_texels as usize;
        CellContext {
            base_texels,
            cos_slope: vec![1.0; n],
            max_error,
            existing_ground,
            texel_ground: existing_ground,
        }
    }

    /// The existing texel under texel `t` of a texture `scale` times finer.
    #[inline]
    pub fn base_index(&self, t: usize, texels: u32, scale: u32) -> usize {
        let (x, y) = (t % texels as usize, t / texels as usize);
        let s = scale.max(1) as usize;
        (y / s) * self.base_texels as usize + x / s
    }

    /// [`CellContext::base_index`] as a function of `t` for a texture of side `texels`,
    /// `scale` times the existing one's (by shifts when both are powers of two).
    #[inline]
    pub fn base_indexer(&self, texels: u32, scale: u32) -> impl Fn(usize) -> usize + Copy {
        let (n, s, base) = (
            texels as usize,
            scale.max(1) as usize,
            self.base_texels as usize,
        );
        let shifts = (n.is_power_of_two() && s.is_power_of_two())
            .then(|| (n.trailing_zeros(), s.trailing_zeros()));
        move |t: usize| match shifts {
            Some((ln, ls)) => ((t >> ln) >> ls) * base + ((t & (n - 1)) >> ls),
            None => (t / n / s) * base + (t % n) / s,
        }
    }

    /// The cosine of the slope at existing texel `b` (1 outside the map).
    #[inline]
    pub fn cos_at(&self, b: usize) -> f32 {
        self.cos_slope.get(b).copied().unwrap_or(1.0)
    }

    /// A photo's resolution (metres) on existing texel `b` from its mean surface footprint
    /// and mean `1 / cos_view` there: `r + ε·cos θ·g`, the pixel size plus the displacement
    /// the TIN's error causes along the photo's rays.
    #[inline]
    pub fn photo_resolution(&self, b: usize, footprint: [f32; 2]) -> f32 {
        footprint[0] + self.max_error * self.cos_at(b) * footprint[1]
    }

    /// The existing texture's resolution (metres) on existing texel `b`:
    /// `ground / max(cos θ, 0.05) + ε`, its ground sample distance stretched along the
    /// fall line, plus the TIN's displacement of a vertical ortho ray.
    #[inline]
    pub fn existing_resolution(&self, b: usize) -> f32 {
        self.existing_ground / self.cos_at(b).max(MIN_COS_SLOPE) + self.max_error
    }
}

/// All photos' contributions to one cell texture on one level.
///
/// Per texel it keeps one record of the same layout as a [`PhotoAccum`]'s ([`TexelSums`]),
/// so that a cell's first photo hands over its memory ([`CellAccum::from_photo`]), with the
/// fields standing for: `coverage` the highest single-photo coverage confidence; `weight`
/// Σ selection weights (best mode: the best photo's); `colour` Σ weight · colour (best mode:
/// the best photo's colour); `footprint` Σ weight · resolution (best mode: the best photo's
/// resolution); `grazing` the largest single-photo selection weight; `clear` the label of
/// the photo with the largest selection weight (1 + its index, exactly as an f32; 0 where no
/// photo gave colour), so that no per-texel array of the whole texture is needed.
#[derive(Clone, Debug, PartialEq)]
pub struct CellAccum {
    /// Blend mode.
    pub mode: BlendMode,
    /// Texture side in texels.
    pub texels: u32,
    /// Factor from the existing texture's texels to this texture's (a power of two).
    pub scale: u32,
    /// The cell's context of the resolution rule.
    pub context: CellContext,
    /// γ of the selection weight `confidence · resolution^−γ`.
    sharpness: f32,
    merged: TexelTiles,
    /// `Some(photo)`: `merged` still holds that one photo's own sums (a [`PhotoAccum`]'s),
    /// turned into this accumulator's records texel by texel as they are read
    /// ([`CellAccum::deferred`]); `None`: the records described above.
    raw: Option<u16>,
}

impl CellAccum {
    /// An empty accumulator of `texels` side, `scale` times the existing texture's.
    pub fn new(
        texels: u32,
        scale: u32,
        mode: BlendMode,
        context: CellContext,
        params: &ConfidenceParams,
    ) -> CellAccum {
        Self::holding(TexelTiles::new(texels), scale, None, mode, context, params)
    }

    /// An accumulator over the records `merged` (its side the texture's), `scale` times the
    /// existing texture's; `raw`: the photo whose raw sums they are ([`CellAccum::deferred`]).
    fn holding(
        merged: TexelTiles,
        scale: u32,
        raw: Option<u16>,
        mode: BlendMode,
        context: CellContext,
        params: &ConfidenceParams,
    ) -> CellAccum {
        CellAccum {
            mode,
            texels: merged.side(),
            scale: scale.max(1),
            context,
            sharpness: params.sharpness_power as f32,
            merged,
            raw,
        }
    }

    /// The accumulator of one photo's deposits `p` (photo number `photo`) without a pass
    /// over its texels: every reader ([`CellAccum::for_each_coloured`] and the accessors)
    /// sees the values [`CellAccum::from_photo`] gives, computed as it reads, bit for bit.
    /// For a photo that no other joins (a lone photo's cells go straight to the blend); a
    /// [`CellAccum::merge`] settles it first. [`CellAccum::settle`] gives the count of
    /// texels `p` gave colour.
    pub fn deferred(
        p: PhotoAccum,
        photo: u16,
        mode: BlendMode,
        context: CellContext,
        params: &ConfidenceParams,
    ) -> CellAccum {
        Self::holding(p.sums, p.scale, Some(photo), mode, context, params)
    }

    /// Whether the records still hold one photo's own sums ([`CellAccum::deferred`]), and
    /// which photo.
    pub fn deferred_photo(&self) -> Option<u16> {
        self.raw
    }

    /// Turns a deferred accumulator's sums into records (as [`CellAccum::from_photo`]) and
    /// returns how many texels its photo gave colour; 0 for one that is not deferred.
    pub fn settle(&mut self) -> u64 {
        let Some(photo) = self.raw.take() else {
            return 0;
        };
        let (texels, scale, mode) = (self.texels, self.scale, self.mode);
        let (context, sharpness) = (&self.context, self.sharpness);
        let label = f32::from(photo.saturating_add(1));
        let mut written = 0;
        let base_index = context.base_indexer(texels, scale);
        self.merged.for_each_mut(|t, s| {
            let r = Self::raw_record(s, context, base_index(t), sharpness, mode, label);
            written += r.is_some() as u64;
            *s = r.unwrap_or_default();
        });
        written
    }

    /// The record one photo's raw sums `s` (label `label`) settle into over existing texel
    /// `b`, `None` where the photo gives no colour.
    #[inline]
    fn raw_record(
        s: &TexelSums,
        ctx: &CellContext,
        b: usize,
        sharpness: f32,
        mode: BlendMode,
        label: f32,
    ) -> Option<TexelSums> {
        Self::photo_texel(s, ctx, b, sharpness)
            .map(|(c, conf, res, w)| Self::first_record(mode, c, conf, res, w, label))
    }

    /// The record of a texel whose first photo (label `label`) has colour `c`, coverage
    /// confidence `conf`, resolution `res` and selection weight `w` there.
    #[inline]
    fn first_record(
        mode: BlendMode,
        c: [f32; 3],
        conf: f32,
        res: f32,
        w: f32,
        label: f32,
    ) -> TexelSums {
        match mode {
            BlendMode::Confidence => TexelSums {
                coverage: conf,
                weight: w,
                colour: c.map(|v| w * v),
                footprint: w * res,
                grazing: w,
                clear: label,
            },
            BlendMode::Best => TexelSums {
                coverage: conf,
                weight: w,
                colour: c,
                footprint: res,
                grazing: w,
                clear: label,
            },
        }
    }

    /// The record of texel `t` as the readers see it (turned from the raw sums if deferred).
    #[inline]
    fn record(&self, t: usize) -> TexelSums {
        let s = self.merged.get(t);
        match self.raw {
            None => *s,
            Some(photo) => self.settled(t, s, photo),
        }
    }

    /// The record a deferred accumulator's raw sums `s` at texel `t` settle into.
    #[inline]
    fn settled(&self, t: usize, s: &TexelSums, photo: u16) -> TexelSums {
        let b = self.context.base_index(t, self.texels, self.scale);
        let label = f32::from(photo.saturating_add(1));
        Self::raw_record(s, &self.context, b, self.sharpness, self.mode, label).unwrap_or_default()
    }

    /// The accumulator of one photo's deposits `p` (photo number `photo`), as
    /// [`CellAccum::new`] followed by [`CellAccum::merge`] of `p` (bit for bit), using `p`'s
    /// memory; also returns how many texels `p` gave colour.
    pub fn from_photo(
        p: PhotoAccum,
        photo: u16,
        mode: BlendMode,
        context: CellContext,
        params: &ConfidenceParams,
    ) -> (CellAccum, u64) {
        let mut acc = CellAccum::deferred(p, photo, mode, context, params);
        let written = acc.settle();
        (acc, written)
    }

    /// A photo's colour, coverage confidence, resolution and selection weight at a texel
    /// over existing texel `b`, from its sums `s` (`None` without colour).
    #[inline]
    fn photo_texel(
        s: &TexelSums,
        ctx: &CellContext,
        b: usize,
        sharpness: f32,
    ) -> Option<([f32; 3], f32, f32, f32)> {
        if !(s.weight > 0.0) {
            return None;
        }
        let c = s.colour.map(|v| (v / s.weight).clamp(0.0, 1.0));
        let conf = (s.weight / s.coverage.max(1.0)).clamp(0.0, 1.0);
        let res = ctx
            .photo_resolution(b, [s.footprint / s.weight, s.grazing / s.weight])
            .max(1e-6);
        // a photo near its occlusion edges keeps a little weight, so that it still gives
        // colour where no other photo does
        let clear = EDGE_FLOOR + (1.0 - EDGE_FLOOR) * (s.clear / s.weight).clamp(0.0, 1.0);
        let w = conf * clear * inverse_power(res, sharpness);
        Some((c, conf, res, if w.is_finite() { w } else { 0.0 }))
    }

    /// Adds the deposits of photo number `photo` (same texture size); returns how many texels
    /// it gave colour.
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    pub fn merge(&mut self, p: &PhotoAccum, photo: u16) -> u64 {
        self.settle();
        let mut written = 0;
        let label = f32::from(photo.saturating_add(1));
        let n = self.merged.len().min(p.sums.len());
        let (ctx, texels, scale, sharpness, mode) = (
            &self.context,
            self.texels,
            self.scale,
            self.sharpness,
            self.mode,
        );
        let merged = &mut self.merged;
        let base_index = ctx.base_indexer(texels, scale);
        p.sums.for_each(|t, ps| {
            if t >= n {
                return;
            }
            let Some((c, conf, res, w)) = Self::photo_texel(ps, ctx, base_index(t), sharpness)
            else {
                return;
            };
            written += 1;
            let Some(s) = merged.get_mut(t) else { return };
            let first = s.clear == 0.0;
            match mode {
                BlendMode::Confidence => {
                    s.weight += w;
                    for k in 0..3 {
                        s.colour[k] += w * c[k];
                    }
                    s.footprint += w * res;
                }
                BlendMode::Best => {
                    // the first photo with colour, then any strictly better one
                    if first || w > s.weight {
                        s.weight = w;
                        s.colour = c;
                        s.footprint = res;
                    }
                }
            }
            if first || w > s.grazing {
                s.clear = label;
                s.grazing = w;
            }
            s.coverage = s.coverage.max(conf);
        });
        written
    }

    /// Per block of `block` texels (row-major over the `⌈texels / block⌉²` grid): whether
    /// footprints reached it (every texel some photo gave colour lies in such a block).
    pub fn touched_blocks(&self, block: u32) -> Vec<bool> {
        self.merged.touched_blocks(block)
    }

    /// Whether some photo gave texel `t` colour.
    #[inline]
    pub fn has_colour(&self, t: usize) -> bool {
        self.record(t).clear != 0.0
    }

    /// The photo (the index given to [`CellAccum::merge`]) with the largest selection weight
    /// at texel `t`, if some photo gave it colour.
    #[inline]
    pub fn best_photo(&self, t: usize) -> Option<u16> {
        label_photo(self.record(t).clear)
    }

    /// Texels of the texture (`texels²`).
    #[inline]
    pub fn len(&self) -> usize {
        self.merged.len()
    }

    /// Texels held by the tiles some photo reached (a measure of the cell's blending work).
    pub fn allocated(&self) -> usize {
        self.merged.allocated()
    }

    /// Whether the texture has no texels.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.merged.len() == 0
    }

    /// The highest single-photo coverage confidence at texel `t`, in [0, 1].
    #[inline]
    pub fn confidence(&self, t: usize) -> f32 {
        self.record(t).coverage
    }

    /// Calls `f(t, colour, confidence, resolution, photo)` for every texel `t` some photo
    /// gave colour (the values of [`CellAccum::colour_at`], [`CellAccum::confidence`],
    /// [`CellAccum::resolution_at`] and [`CellAccum::best_photo`]), in tile order: only the
    /// tiles footprints reached are visited.
    pub fn for_each_coloured(&self, mut f: impl FnMut(usize, [f32; 3], f32, f32, Option<u16>)) {
        let mode = self.mode;
        let mut visit = |t: usize, s: &TexelSums| {
            let Some(photo) = label_photo(s.clear) else {
                return;
            };
            let (colour, res) = match mode {
                BlendMode::Confidence if s.weight > 0.0 => (
                    s.colour.map(|c| (c / s.weight).clamp(0.0, 1.0)),
                    s.footprint / s.weight,
                ),
                BlendMode::Confidence => ([0.0; 3], f32::INFINITY),
                BlendMode::Best => (
                    s.colour,
                    if s.weight > 0.0 {
                        s.footprint
                    } else {
                        f32::INFINITY
                    },
                ),
            };
            f(t, colour, s.coverage, res, Some(photo));
        };
        match self.raw {
            None => self.merged.for_each(visit),
            Some(photo) => {
                // (the records `settle` would write, made as they are read)
                let (ctx, sharpness) = (&self.context, self.sharpness);
                let base_index = ctx.base_indexer(self.texels, self.scale);
                let label = f32::from(photo.saturating_add(1));
                self.merged.for_each(|t, s| {
                    if let Some(r) = Self::raw_record(s, ctx, base_index(t), sharpness, mode, label)
                    {
                        visit(t, &r);
                    }
                });
            }
        }
    }

    /// The combined photo colour (working space 0..1) at texel `t`, if any photo gave it colour.
    pub fn colour_at(&self, t: usize) -> Option<[f32; 3]> {
        if !self.has_colour(t) {
            return None;
        }
        let s = self.record(t);
        Some(match self.mode {
            BlendMode::Confidence if s.weight > 0.0 => {
                s.colour.map(|c| (c / s.weight).clamp(0.0, 1.0))
            }
            BlendMode::Confidence => [0.0; 3],
            BlendMode::Best => s.colour,
        })
    }

    /// The combined photo resolution (metres) at texel `t` (the weighted mean of the photos',
    /// or the best photo's); infinite without usable colour.
    pub fn resolution_at(&self, t: usize) -> f32 {
        let s = self.record(t);
        match self.mode {
            BlendMode::Confidence if s.weight > 0.0 => s.footprint / s.weight,
            BlendMode::Best if self.has_colour(t) && s.weight > 0.0 => s.footprint,
            _ => f32::INFINITY,
        }
    }
}
