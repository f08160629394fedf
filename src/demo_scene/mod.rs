//! The embedded demo scene: a procedural terrain with real cliffs, deterministic from a seed.
//!
//! Data types: [`DemoScene`] (parameters) produces a [`Dem`] and an [`Ortho`] on the same grid.
//! The terrain has a box-like plateau (mesa) with ~89° walls, a meandering canyon with ~80°
//! walls, an escarpment (cliff band) and fractal hills. Its colour is a **solid texture**
//! ([`DemoScene::surface_colour`]): a function of the 3D surface point (rock strata by height
//! with fine detail, noise, vegetation on gentle slopes), so later stages can compare any
//! texel with ground truth. The ortho image is the top-down, area-averaged view of it (in
//! linear light), which smears the walls exactly as real orthophotos do.
//!
//! Ground truth for photo projection: [`DemoScene::photo_shots`] places ground cameras
//! from the scene's geometry, [`DemoScene::render_truth_photo`] ray-traces what they see,
//! [`DemoScene::write_demo_photos`] writes them as a `photos.json` set, and [`texel_truth`]
//! scores a store's textures texel by texel against the solid texture (docs/projection.md).
//!
//! Placement: the north-west sample lies at UTM-sized coordinates (default x = 431 000,
//! y = 6 878 000), so the whole pipeline is exercised at realistic magnitudes.

mod photos;
mod tracer;
mod truth;

pub use photos::{DemoPhotoOptions, PhotoShot, SKY_COLOUR};
pub(crate) use tracer::sees_with;
pub use tracer::{DemHit, DemTracer};
pub use truth::{
    FLAT_DEG, STEEP_DEG, TextureChoice, TruthReport, texel_truth, texel_truth_covered,
    texel_truth_with,
};

use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
use rayon::prelude::*;

use crate::colour::{linear_to_srgb, srgb_to_linear};
use crate::dem::Dem;
use crate::error::Result;
use crate::georef::GridGeoref;
use crate::ortho::Ortho;

/// Parameters of the demo scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemoScene {
    /// Seed of all noise; the same seed gives the same scene bit for bit.
    pub seed: u32,
    /// Samples per side of the DEM (>= 17).
    pub samples: usize,
    /// Sample spacing in metres.
    pub spacing: f64,
    /// World x of the north-west sample centre.
    pub origin_x: f64,
    /// World y of the north-west sample centre.
    pub origin_y: f64,
    /// Heights of the scene's walls.
    pub relief: Relief,
    /// Factor on the demo cameras' candidate distances from their targets (> 0; 1 = the
    /// default 150–350 m).
    pub photo_distance: f64,
}

/// Heights of the demo scene's three kinds of wall, metres (each >= 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relief {
    /// Height of the plateau above its surroundings (~89° walls). Default 70.
    pub plateau: f64,
    /// Depth of the canyon (~80° walls, steeper when deeper). Default 90.
    pub canyon: f64,
    /// Height of the escarpment (~85° wall). Default 45.
    pub escarpment: f64,
}

impl Default for Relief {
    fn default() -> Self {
        Relief {
            plateau: 70.0,
            canyon: 90.0,
            escarpment: 45.0,
        }
    }
}

impl Default for DemoScene {
    fn default() -> Self {
        DemoScene {
            seed: 7,
            samples: 513,
            spacing: 2.0,
            origin_x: 431_000.0,
            origin_y: 6_878_000.0,
            relief: Relief::default(),
            photo_distance: 1.0,
        }
    }
}

impl DemoScene {
    /// A second evaluation scene unlike the default one: a 1-m DEM of 1025² samples, taller
    /// walls (plateau 110 m, canyon 120 m, escarpment 65 m) and cameras at 0.7 × the default
    /// distances, with another seed.
    pub fn tall_walls() -> DemoScene {
        DemoScene {
            seed: 23,
            samples: 1025,
            spacing: 1.0,
            relief: Relief {
                plateau: 110.0,
                canyon: 120.0,
                escarpment: 65.0,
            },
            photo_distance: 0.7,
            ..DemoScene::default()
        }
    }
}

/// Corner rounding of the plateau (its walls stand this far outside the rectangle), metres.
const PLATEAU_ROUNDING: f64 = 4.0;

/// Noise sources, built once per scene.
struct Noises {
    hills: Fbm<Perlin>,
    detail: Fbm<Perlin>,
    colour: Perlin,
}

impl DemoScene {
    /// Side length of the terrain in metres.
    pub fn size_m(&self) -> f64 {
        (self.samples - 1) as f64 * self.spacing
    }

    fn noises(&self) -> Noises {
        Noises {
            hills: Fbm::<Perlin>::new(self.seed)
                .set_octaves(5)
                .set_frequency(1.0 / 350.0),
            detail: Fbm::<Perlin>::new(self.seed.wrapping_add(1))
                .set_octaves(3)
                .set_frequency(1.0 / 40.0),
            colour: Perlin::new(self.seed.wrapping_add(2)),
        }
    }

    /// Terrain height at scene-local (east, south) metres from the north-west sample.
    fn height_local(&self, n: &Noises, e: f64, s: f64) -> f64 {
        let l = self.size_m();
        let v = s / l;
        // Rolling hills and a gentle tilt.
        let mut h = 600.0 + 28.0 * n.hills.get([e, s]) + 2.0 * n.detail.get([e, s]) - 40.0 * v;
        // Escarpment: a cliff band across the south of the scene (45 m high by default), ~85° wall.
        let line = self.escarpment_line(n, e);
        h += self.relief.escarpment * smoothstep(-2.0, 2.0, line - s);
        // Box-like plateau (mesa): rounded rectangle (70 m high by default), ~89° walls.
        let [cx, cy, hx, hy] = self.plateau_rect();
        let (dx, dy) = ((e - cx).abs() - hx, (s - cy).abs() - hy);
        let sd = (dx.max(0.0).hypot(dy.max(0.0))) + dx.max(dy).min(0.0) - PLATEAU_ROUNDING;
        h += self.relief.plateau * smoothstep(0.6, -0.6, sd);
        // Meandering canyon (90 m deep by default) with a 20 m floor and ~80° walls.
        let d = (e - self.canyon_axis(s)).abs();
        h -= self.relief.canyon * (1.0 - smoothstep(10.0, 26.0, d));
        h
    }

    /// Plateau rectangle `[centre east, centre south, half width, half height]` (scene-local
    /// metres from the north-west sample); the walls stand [`PLATEAU_ROUNDING`] outside it.
    fn plateau_rect(&self) -> [f64; 4] {
        let l = self.size_m();
        [0.3 * l, 0.35 * l, 0.11 * l, 0.08 * l]
    }

    /// Scene-local east coordinate of the canyon's axis at south coordinate `s`.
    fn canyon_axis(&self, s: f64) -> f64 {
        0.72 * self.size_m() + 40.0 * (s / 120.0).sin()
    }

    /// Scene-local south coordinate of the escarpment's wall at east coordinate `e` (the
    /// ground north of it is higher).
    fn escarpment_line(&self, n: &Noises, e: f64) -> f64 {
        0.78 * self.size_m() + 18.0 * (e / 97.0).sin() + 6.0 * n.detail.get([e * 0.5, 3.0])
    }

    /// Terrain height at world (x, y).
    pub fn height(&self, x: f64, y: f64) -> f64 {
        self.height_local(&self.noises(), x - self.origin_x, self.origin_y - y)
    }

    /// Ground-truth colour of the surface point (x, y, z) (world), sRGB 0..1.
    /// `slope_deg` is the surface slope there (vegetation grows on gentle slopes only).
    pub fn surface_colour(&self, x: f64, y: f64, z: f64, slope_deg: f64) -> [f64; 3] {
        surface_colour(&self.noises(), self, x, y, z, slope_deg)
    }

    /// [`DemoScene::surface_colour`] with the noise tables built once (for many evaluations).
    pub fn surface_colour_fn(&self) -> impl Fn(f64, f64, f64, f64) -> [f64; 3] + Sync + '_ {
        let n = self.noises();
        move |x, y, z, slope| surface_colour(&n, self, x, y, z, slope)
    }

    /// Generates the DEM and the ortho image (same grid, area-averaged top-down colour).
    pub fn generate(&self) -> Result<(Dem, Ortho)> {
        let n = self.noises();
        let w = self.samples;
        let sp = self.spacing;
        let heights: Vec<f32> = (0..w * w)
            .into_par_iter()
            .map(|i| self.height_local(&n, (i % w) as f64 * sp, (i / w) as f64 * sp) as f32)
            .collect();
        let georef = GridGeoref::new(self.origin_x, self.origin_y, sp);
        let dem = Dem::from_heights(w, w, heights, georef)?;
        // Ortho: 4x4 supersampled top-down view of the solid texture, averaged in linear light
        // (as a camera integrates).
        const SS: usize = 4;
        let pixels: Vec<[u8; 4]> = (0..w * w)
            .into_par_iter()
            .map(|i| {
                let (col, row) = ((i % w) as f64, (i / w) as f64);
                let mut acc = [0.0; 3];
                for sy in 0..SS {
                    for sx in 0..SS {
                        let e = (col - 0.5 + (sx as f64 + 0.5) / SS as f64) * sp;
                        let s = (row - 0.5 + (sy as f64 + 0.5) / SS as f64) * sp;
                        let z = self.height_local(&n, e, s);
                        let gx =
                            self.height_local(&n, e + 0.25, s) - self.height_local(&n, e - 0.25, s);
                        let gy =
                            self.height_local(&n, e, s + 0.25) - self.height_local(&n, e, s - 0.25);
                        let slope = (gx.hypot(gy) / 0.5).atan().to_degrees();
                        let c = surface_colour(
                            &n,
                            self,
                            self.origin_x + e,
                            self.origin_y - s,
                            z,
                            slope,
                        );
                        for k in 0..3 {
                            acc[k] += srgb_to_linear(c[k]);
                        }
                    }
                }
                let q = |v: f64| {
                    (linear_to_srgb(v / (SS * SS) as f64) * 255.0)
                        .round()
                        .clamp(0.0, 255.0) as u8
                };
                [q(acc[0]), q(acc[1]), q(acc[2]), 255]
            })
            .collect();
        let image = image::RgbaImage::from_raw(w as u32, w as u32, pixels.into_flattened())
            .ok_or_else(|| crate::Error::BadOption("demo ortho size mismatch".into()))?;
        Ok((dem, Ortho { image, georef }))
    }
}

fn surface_colour(n: &Noises, sc: &DemoScene, x: f64, y: f64, z: f64, slope_deg: f64) -> [f64; 3] {
    let (e, s) = (x - sc.origin_x, sc.origin_y - y);
    // Rock strata: bands by height with fine (0.8 m) sub-bands and a wavy 3D perturbation.
    let zz = z + 1.5 * n.colour.get([e / 25.0, s / 25.0, z / 25.0]);
    let band = (zz / 6.0).rem_euclid(1.0);
    let fine = 0.5 + 0.5 * (zz * std::f64::consts::TAU / 0.8).sin();
    let grain = n.colour.get([e / 1.3, s / 1.3, z / 1.3]);
    let rock = [
        0.45 + 0.25 * band + 0.10 * fine + 0.08 * grain,
        0.38 + 0.15 * band + 0.08 * fine + 0.08 * grain,
        0.30 + 0.05 * band + 0.06 * fine + 0.08 * grain,
    ];
    // Vegetation on gentle slopes, patchy.
    let patch = n.colour.get([e / 60.0, s / 60.0, 0.5]);
    let veg = smoothstep(38.0, 25.0, slope_deg) * smoothstep(-0.4, 0.1, patch);
    let green = [
        0.22 + 0.05 * grain,
        0.36 + 0.08 * grain,
        0.16 + 0.03 * grain,
    ];
    let mut c = [0.0; 3];
    for k in 0..3 {
        c[k] = (rock[k] * (1.0 - veg) + green[k] * veg).clamp(0.0, 1.0);
    }
    c
}

/// Hermite smoothstep from 0 at `a` to 1 at `b` (`a > b` gives a falling step).
fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_and_has_cliffs() {
        let sc = DemoScene {
            samples: 129,
            spacing: 8.0,
            ..Default::default()
        };
        let (a, oa) = sc.generate().unwrap();
        let (b, ob) = sc.generate().unwrap();
        assert_eq!(a.heights, b.heights);
        assert_eq!(oa.image, ob.image);
        let full = DemoScene::default();
        let (dem, _) = full.generate().unwrap();
        // Steepest slope between adjacent samples must be near vertical (box plateau walls).
        let mut max_slope: f64 = 0.0;
        for r in 0..dem.height {
            for c in 0..dem.width - 1 {
                let d = (dem.at(r, c + 1) - dem.at(r, c)).abs() as f64;
                max_slope = max_slope.max((d / full.spacing).atan().to_degrees());
            }
        }
        assert!(max_slope > 85.0, "max slope {max_slope}");
    }
}
