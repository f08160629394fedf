//! Tests of `cliffmap::resample`: constants, gradients, degenerate charts, fills,
//! convergence of the subtexel estimate, orthographic downsampling, determinism.

use cliffmap::GridGeoref;
use cliffmap::resample::{
    ChartMesh, Fill, MIN_FOOTPRINT_AREA, Mode, PixelMap, ResampleOptions, Resampled, Source, fill,
    resample,
};
use image::{Rgba, RgbaImage};

const ALL_MODES: [Mode; 6] = [
    Mode::Subtexel(1),
    Mode::Subtexel(2),
    Mode::Subtexel(4),
    Mode::Subtexel(8),
    Mode::Bilinear,
    Mode::Exact,
];

/// An owned chart.
struct Chart {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    uvs: Vec<[f64; 2]>,
}

impl Chart {
    fn mesh(&self) -> ChartMesh<'_> {
        ChartMesh {
            positions: &self.positions,
            triangles: &self.triangles,
            uvs: &self.uvs,
        }
    }

    /// A `(nx+1) x (ny+1)` vertex grid, two triangles per quad; `f(i, j)` gives position and uv.
    fn grid(nx: u32, ny: u32, f: impl Fn(u32, u32) -> ([f64; 3], [f64; 2])) -> Chart {
        let (mut positions, mut uvs, mut triangles) = (vec![], vec![], vec![]);
        for j in 0..=ny {
            for i in 0..=nx {
                let (p, uv) = f(i, j);
                positions.push(p);
                uvs.push(uv);
            }
        }
        let id = |i: u32, j: u32| j * (nx + 1) + i;
        for j in 0..ny {
            for i in 0..nx {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Chart {
            positions,
            triangles,
            uvs,
        }
    }

    /// The position at texture point `uv`, by barycentric interpolation in the triangle
    /// that contains it (None outside the chart).
    fn position_at(&self, uv: [f64; 2]) -> Option<[f64; 3]> {
        for t in &self.triangles {
            let [a, b, c] = t.map(|k| self.uvs[k as usize]);
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if det.abs() < 1e-15 {
                continue;
            }
            let l1 = ((uv[0] - a[0]) * (c[1] - a[1]) - (uv[1] - a[1]) * (c[0] - a[0])) / det;
            let l2 = ((b[0] - a[0]) * (uv[1] - a[1]) - (b[1] - a[1]) * (uv[0] - a[0])) / det;
            let l0 = 1.0 - l1 - l2;
            if l0 >= -1e-9 && l1 >= -1e-9 && l2 >= -1e-9 {
                let [p0, p1, p2] = t.map(|k| self.positions[k as usize]);
                return Some(std::array::from_fn(|k| {
                    l0 * p0[k] + l1 * p1[k] + l2 * p2[k]
                }));
            }
        }
        None
    }
}

/// A ruled wall over `x in [x0, x1]`, `y in [y0, y1]` (world units = source pixels):
/// z(x) = height * (1 + tanh((x - xm) / width)) / 2, so the wall is near-vertical when
/// `width` is small. uv: u = arc length along x / total, v = (y1 - y) / (y1 - y0), mapped into
/// `[m, 1 - m]²`. Area-preserving up to the per-axis scale (exact for a ruled surface).
/// The wall is finally rotated by `angle` about the rectangle's centre in x, y.
fn wall_chart(
    n: u32,
    [x0, x1, y0, y1]: [f64; 4],
    height: f64,
    width: f64,
    m: f64,
    angle: f64,
) -> Chart {
    let (ca, sa) = (angle.cos(), angle.sin());
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let xm = 0.5 * (x0 + x1);
    let z = |x: f64| height * 0.5 * (1.0 + ((x - xm) / width).tanh());
    // x samples denser across the wall
    let xs: Vec<f64> = (0..=n)
        .map(|i| {
            let s = i as f64 / n as f64 * 2.0 - 1.0;
            xm + 0.5 * (x1 - x0) * (s.signum() * s.abs().powf(1.5))
        })
        .collect();
    let mut arc = vec![0.0];
    for k in 1..xs.len() {
        let (dx, dz) = (xs[k] - xs[k - 1], z(xs[k]) - z(xs[k - 1]));
        arc.push(arc[k - 1] + (dx * dx + dz * dz).sqrt());
    }
    let total = arc[arc.len() - 1];
    Chart::grid(n, n, |i, j| {
        let y = y1 - (y1 - y0) * j as f64 / n as f64;
        let x = xs[i as usize];
        let (dx, dy) = (x - cx, y - cy);
        (
            [cx + ca * dx - sa * dy, cy + sa * dx + ca * dy, z(x)],
            [
                m + (1.0 - 2.0 * m) * arc[i as usize] / total,
                m + (1.0 - 2.0 * m) * j as f64 / n as f64,
            ],
        )
    })
}

/// The orthographic chart of the square `[x0, x0 + size] x [y0, y0 + size]`: uv = planar
/// position over the square (v down = y decreasing), optionally rotated by `angle` about the
/// square's centre in position space.
fn ortho_chart(x0: f64, y0: f64, size: f64, angle: f64) -> Chart {
    let (c, s) = (angle.cos(), angle.sin());
    let (cx, cy) = (x0 + 0.5 * size, y0 + 0.5 * size);
    Chart::grid(4, 4, |i, j| {
        let (u, v) = (i as f64 / 4.0, j as f64 / 4.0);
        let (px, py) = (x0 + u * size - cx, y0 + size - v * size - cy);
        ([cx + c * px - s * py, cy + s * px + c * py, 0.0], [u, v])
    })
}

/// World = pixel frame of a `w x h` image: pixel (c, r) centre at x = c + 0.5, y = h - r - 0.5,
/// so the image spans x in [0, w], y in [0, h].
fn pixel_frame(h: u32) -> PixelMap {
    PixelMap::from_georef(&GridGeoref::new(0.5, h as f64 - 0.5, 1.0), [0.0, 0.0])
}

fn opts(mode: Mode, texels: u32) -> ResampleOptions {
    ResampleOptions {
        mode,
        texels,
        fill: Fill::AverageBorder,
        gutter_texels: 2,
    }
}

fn run(chart: &Chart, img: &RgbaImage, o: ResampleOptions) -> Resampled {
    let src = Source {
        image: img,
        to_pixel: pixel_frame(img.height()),
    };
    match resample(&chart.mesh(), &src, &o) {
        Ok(r) => r,
        Err(e) => panic!("resample failed: {e}"),
    }
}

fn check_consistency(r: &Resampled) {
    let s = r.stats;
    let n = r.covered.len();
    assert_eq!(n as u32, r.image.width() * r.image.height());
    assert_eq!(s.covered_texels, r.covered.iter().filter(|&&c| c).count());
    assert_eq!(s.known_texels + s.unknown_covered_texels, s.covered_texels);
    assert_eq!(
        s.known_texels + s.gutter_texels + s.filled_texels,
        n,
        "{s:?}"
    );
    let alpha255 = r.image.pixels().filter(|p| p[3] == 255).count();
    assert_eq!(alpha255, s.known_texels);
    for (p, &c) in r.image.pixels().zip(&r.covered) {
        assert!(
            p[3] == 0 || (p[3] == 255 && c),
            "alpha {} on covered={c}",
            p[3]
        );
    }
}

/// A deterministic pseudo-random generator (xorshift).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn byte(&mut self) -> u8 {
        (self.next() >> 32) as u8
    }
}

fn random_image(w: u32, h: u32, seed: u64) -> RgbaImage {
    let mut rng = Rng(seed);
    RgbaImage::from_fn(w, h, |_, _| Rgba([rng.byte(), rng.byte(), rng.byte(), 255]))
}

fn charts_for_general_tests() -> Vec<(&'static str, Chart)> {
    vec![
        (
            "steep wall",
            wall_chart(24, [8.0, 56.0, 8.0, 56.0], 60.0, 0.8, 0.1, 0.0),
        ),
        (
            "rotated steep wall",
            wall_chart(24, [12.0, 52.0, 12.0, 52.0], 60.0, 0.8, 0.1, 0.6),
        ),
        (
            "gentle wall",
            wall_chart(12, [8.0, 56.0, 8.0, 56.0], 20.0, 10.0, 0.05, -0.3),
        ),
        ("ortho", ortho_chart(10.0, 10.0, 40.0, 0.0)),
        ("rotated ortho", ortho_chart(12.0, 12.0, 36.0, 0.5)),
    ]
}

#[test]
fn constant_colour_in_constant_colour_out_every_mode_and_fill() {
    let colour = [200u8, 100, 50];
    let mut img = RgbaImage::from_pixel(64, 64, Rgba([colour[0], colour[1], colour[2], 255]));
    // unknown pixels must not leak into the result
    for r in 0..64 {
        for c in 0..6 {
            img.put_pixel(c, r, Rgba([0, 0, 0, 0]));
        }
    }
    // a chart partly over unknown pixels and partly beyond the image
    let mut charts = charts_for_general_tests();
    charts.push(("over the edge", ortho_chart(-8.0, 30.0, 40.0, 0.3)));
    for (name, chart) in &charts {
        for mode in ALL_MODES {
            for fill in [Fill::AverageBorder, Fill::PullPush] {
                for texels in [17, 64, 128] {
                    let r = run(
                        chart,
                        &img,
                        ResampleOptions {
                            mode,
                            texels,
                            fill,
                            gutter_texels: 3,
                        },
                    );
                    check_consistency(&r);
                    assert!(r.stats.known_texels > 0, "{name} {mode:?}");
                    for (k, p) in r.image.pixels().enumerate() {
                        assert_eq!(
                            p.0[..3],
                            colour,
                            "{name} {mode:?} {fill:?} {texels}: texel {k}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn linear_gradient_matches_the_analytic_value() {
    // colour = a + g . (col, row) per channel
    let grads = [[2.0, 0.0], [0.0, 1.5], [1.0, -1.0]];
    let base = [20.0, 30.0, 120.0];
    let f = |k: usize, c: f64, r: f64| base[k] + grads[k][0] * c + grads[k][1] * r;
    let img = RgbaImage::from_fn(64, 64, |c, r| {
        let v = |k| f(k, c as f64, r as f64).round() as u8;
        Rgba([v(0), v(1), v(2), 255])
    });
    let pm = pixel_frame(64);
    for (name, chart) in charts_for_general_tests() {
        for mode in ALL_MODES {
            let texels = 48;
            let r = run(&chart, &img, opts(mode, texels));
            check_consistency(&r);
            let mut worst: f64 = 0.0;
            for j in 0..texels {
                for i in 0..texels {
                    let k = (j * texels + i) as usize;
                    if !r.covered[k] {
                        continue;
                    }
                    let uv = [
                        (i as f64 + 0.5) / texels as f64,
                        (j as f64 + 0.5) / texels as f64,
                    ];
                    let Some(p) = chart.position_at(uv) else {
                        panic!("{name}: covered texel {k} outside chart")
                    };
                    let [c, rr] = pm.apply(p[0], p[1]);
                    let px = r.image.get_pixel(i, j);
                    assert_eq!(px[3], 255, "{name} {mode:?}");
                    for ch in 0..3 {
                        // area averages of a pixel-constant linear function deviate from the
                        // value at the footprint centre by at most half a pixel of gradient;
                        // coarse subtexel estimates mis-weight the footprint's boundary pixels.
                        let g = grads[ch][0].abs() + grads[ch][1].abs();
                        let tol = match mode {
                            Mode::Subtexel(1) => 1.5 * g + 0.6,
                            Mode::Subtexel(2) => g + 0.6,
                            _ => 0.5 * g + 0.6,
                        };
                        let err = (px[ch] as f64 - f(ch, c, rr)).abs();
                        worst = worst.max(err - tol);
                        assert!(
                            err <= tol,
                            "{name} {mode:?} texel ({i},{j}) ch {ch}: {} vs {:.2}",
                            px[ch],
                            f(ch, c, rr)
                        );
                    }
                }
            }
        }
    }
}

/// A wall whose x,y projection is exactly degenerate: the middle column of quads is vertical.
fn vertical_wall_chart() -> Chart {
    let xs: [f64; 6] = [10.0, 20.0, 30.0, 30.0, 40.0, 50.0];
    let zs = [0.0, 0.0, 0.0, 30.0, 30.0, 30.0];
    let mut arc = vec![0.0];
    for k in 1..6 {
        arc.push(arc[k - 1] + (xs[k] - xs[k - 1]).hypot(zs[k] - zs[k - 1]));
    }
    let total = arc[5];
    Chart::grid(5, 6, |i, j| {
        let y = 50.0 - 40.0 * j as f64 / 6.0;
        (
            [xs[i as usize], y, zs[i as usize]],
            [arc[i as usize] / total, j as f64 / 6.0],
        )
    })
}

#[test]
fn collapsed_and_degenerate_charts_give_valid_colours() {
    let colour = [13u8, 250, 77];
    let flat = RgbaImage::from_pixel(64, 64, Rgba([colour[0], colour[1], colour[2], 255]));
    let grad = RgbaImage::from_fn(64, 64, |c, r| {
        Rgba([(c * 4) as u8, (r * 4) as u8, 128, 255])
    });
    let wall = vertical_wall_chart();
    // zero-area uv triangles and triangles collapsed in x,y mixed into a valid chart
    let mut mixed = ortho_chart(10.0, 10.0, 40.0, 0.2);
    let nv = mixed.positions.len() as u32;
    mixed
        .positions
        .extend([[20.0, 20.0, 0.0], [20.0, 20.0, 5.0], [20.0, 20.0, 9.0]]);
    mixed.uvs.extend([[0.2, 0.2], [0.4, 0.4], [0.6, 0.6]]);
    mixed.triangles.push([nv, nv + 1, nv + 2]); // collinear uvs: covers nothing
    mixed.triangles.push([0, 0, 1]); // repeated vertex
    // a chart where every vertex sits on one point of the source (all footprints collapse)
    let point = Chart::grid(3, 3, |i, j| {
        (
            [25.0, 25.0, (i + j) as f64],
            [i as f64 / 3.0, j as f64 / 3.0],
        )
    });
    // a chart entirely collinear in uv
    let line = Chart::grid(3, 3, |i, j| {
        (
            [i as f64 * 10.0, j as f64 * 10.0, 0.0],
            [i as f64 / 3.0, i as f64 / 3.0],
        )
    });
    // a chart far outside the source image
    let away = ortho_chart(1000.0, 1000.0, 30.0, 0.0);
    for (name, chart) in [
        ("vertical wall", &wall),
        ("mixed", &mixed),
        ("point", &point),
        ("line", &line),
        ("away", &away),
    ] {
        for mode in ALL_MODES {
            for texels in [1, 7, 64] {
                let r = run(chart, &flat, opts(mode, texels));
                check_consistency(&r);
                for p in r.image.pixels() {
                    if p[3] == 255 {
                        assert_eq!(p.0[..3], colour, "{name} {mode:?}");
                    }
                }
                let r = run(
                    chart,
                    &grad,
                    ResampleOptions {
                        fill: Fill::PullPush,
                        ..opts(mode, texels)
                    },
                );
                check_consistency(&r);
                for p in r.image.pixels().filter(|p| p[3] == 255) {
                    assert!(
                        p[0] <= 252 && p[1] <= 252 && p[2] == 128,
                        "{name} {mode:?}: {p:?}"
                    );
                }
            }
        }
    }
    // the vertical wall and the point chart exercise the fallback; the line covers nothing
    let r = run(&wall, &flat, opts(Mode::Subtexel(4), 64));
    assert!(r.stats.bilinear_fallbacks > 0 && r.stats.known_texels == r.stats.covered_texels);
    let r = run(&point, &flat, opts(Mode::Exact, 16));
    assert_eq!(r.stats.bilinear_fallbacks, 256);
    assert_eq!(
        run(&line, &flat, opts(Mode::Exact, 16))
            .stats
            .covered_texels,
        0
    );
    assert_eq!(
        run(&away, &flat, opts(Mode::Exact, 16)).stats.known_texels,
        0
    );
    let _ = MIN_FOOTPRINT_AREA;
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let img = RgbaImage::from_pixel(8, 8, Rgba([1, 2, 3, 255]));
    let src = Source {
        image: &img,
        to_pixel: pixel_frame(8),
    };
    let c = ortho_chart(0.0, 0.0, 8.0, 0.0);
    let good = opts(Mode::Exact, 8);
    assert!(resample(&c.mesh(), &src, &good).is_ok());
    let mut bad = c.triangles.clone();
    bad.push([0, 1, 999]);
    let m = ChartMesh {
        triangles: &bad,
        ..c.mesh()
    };
    assert!(
        resample(&m, &src, &good)
            .unwrap_err()
            .to_string()
            .contains("999")
    );
    let mut uvs = c.uvs.clone();
    uvs[3] = [f64::NAN, 0.0];
    assert!(
        resample(
            &ChartMesh {
                uvs: &uvs,
                ..c.mesh()
            },
            &src,
            &good
        )
        .is_err()
    );
    assert!(
        resample(
            &ChartMesh {
                uvs: &c.uvs[1..],
                ..c.mesh()
            },
            &src,
            &good
        )
        .is_err()
    );
    let mut pos = c.positions.clone();
    pos[0][2] = f64::INFINITY;
    assert!(
        resample(
            &ChartMesh {
                positions: &pos,
                ..c.mesh()
            },
            &src,
            &good
        )
        .is_err()
    );
    for o in [
        opts(Mode::Exact, 0),
        opts(Mode::Subtexel(0), 8),
        opts(Mode::Subtexel(65), 8),
        opts(Mode::Exact, 100_000),
    ] {
        assert!(resample(&c.mesh(), &src, &o).is_err(), "{o:?}");
    }
    let empty = RgbaImage::new(0, 0);
    let r = resample(
        &c.mesh(),
        &Source {
            image: &empty,
            to_pixel: pixel_frame(0),
        },
        &good,
    );
    assert_eq!(r.map(|r| r.stats.known_texels).ok(), Some(0));
}

#[test]
// indexed loops: each index serves more than one array or lookup
#[allow(clippy::needless_range_loop)]
fn fills_never_touch_known_texels_and_leave_nothing_empty() {
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let img = random_image(40, 30, 7);
    let assigned: Vec<bool> = (0..1200)
        .map(|k| (k % 40 > 10 && k % 40 < 25 && k / 40 > 5) || rng.next().is_multiple_of(17))
        .collect();
    // average border colour, computed independently
    let (mut s, mut n) = ([0u64; 3], 0u64);
    for k in 0..1200usize {
        let (x, y) = ((k % 40) as i64, (k / 40) as i64);
        if !assigned[k] {
            continue;
        }
        let borders = [(-1, 0), (1, 0), (0, -1), (0, 1)]
            .iter()
            .any(|&(dx, dy): &(i64, i64)| {
                let (a, b) = (x + dx, y + dy);
                (0..40).contains(&a) && (0..30).contains(&b) && !assigned[(b * 40 + a) as usize]
            });
        if borders {
            let p = img.get_pixel(x as u32, y as u32);
            for c in 0..3 {
                s[c] += p[c] as u64;
            }
            n += 1;
        }
    }
    let expect = s.map(|v| ((v + n / 2) / n) as u8);
    let mut a = img.clone();
    assert_eq!(
        fill::fill_average_border(&mut a, &assigned),
        assigned.iter().filter(|&&x| !x).count()
    );
    let mut b = img.clone();
    fill::fill_pull_push(&mut b, &assigned);
    let lo = (0..3)
        .map(|c| {
            img.pixels()
                .zip(&assigned)
                .filter(|p| *p.1)
                .map(|p| p.0[c])
                .min()
                .unwrap_or(0)
        })
        .collect::<Vec<_>>();
    let hi = (0..3)
        .map(|c| {
            img.pixels()
                .zip(&assigned)
                .filter(|p| *p.1)
                .map(|p| p.0[c])
                .max()
                .unwrap_or(0)
        })
        .collect::<Vec<_>>();
    for k in 0..1200usize {
        let (x, y) = ((k % 40) as u32, (k / 40) as u32);
        let (o, pa, pb) = (img.get_pixel(x, y), a.get_pixel(x, y), b.get_pixel(x, y));
        assert_eq!(o[3], pa[3]);
        assert_eq!(o[3], pb[3]);
        if assigned[k] {
            assert_eq!(o, pa);
            assert_eq!(o, pb);
        } else {
            assert_eq!(pa.0[..3], expect);
            for c in 0..3 {
                assert!(pb[c] >= lo[c] && pb[c] <= hi[c]);
            }
        }
    }
    // through resample: covered known texels identical whatever the fill and gutter
    let src_img = random_image(64, 64, 11);
    let chart = wall_chart(16, [8.0, 56.0, 8.0, 56.0], 50.0, 1.0, 0.15, 0.0);
    let runs: Vec<Resampled> = [
        (Fill::AverageBorder, 0),
        (Fill::AverageBorder, 4),
        (Fill::PullPush, 0),
        (Fill::PullPush, 3),
    ]
    .into_iter()
    .map(|(fill, gutter_texels)| {
        run(
            &chart,
            &src_img,
            ResampleOptions {
                mode: Mode::Subtexel(2),
                texels: 64,
                fill,
                gutter_texels,
            },
        )
    })
    .collect();
    for r in &runs {
        check_consistency(r);
        assert!(r.stats.filled_texels + r.stats.gutter_texels > 0);
        for (k, (p, q)) in r.image.pixels().zip(runs[0].image.pixels()).enumerate() {
            if q[3] == 255 {
                assert_eq!(p, q, "known texel {k} changed by the fill");
            } else {
                assert_eq!(p[3], 0);
            }
        }
    }
    // gutter: the ring next to known texels holds neighbour colours, not the fill colour
    assert!(runs[1].stats.gutter_texels > 0);
}

fn chessboard(w: u32, h: u32, square: u32) -> RgbaImage {
    RgbaImage::from_fn(w, h, |c, r| {
        let v = if (c / square + r / square).is_multiple_of(2) {
            0
        } else {
            255
        };
        Rgba([v, 255 - v, v / 2, 255])
    })
}

fn rmse_known(a: &Resampled, b: &Resampled) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (p, q) in a.image.pixels().zip(b.image.pixels()) {
        if p[3] == 255 && q[3] == 255 {
            for c in 0..3 {
                s += (p[c] as f64 - q[c] as f64).powi(2);
                n += 1;
            }
        }
    }
    assert!(n > 0);
    (s / n as f64).sqrt()
}

#[test]
fn subtexel_estimate_converges_to_exact() {
    let img = chessboard(96, 96, 2);
    for (name, chart) in [
        ("rotated ortho", ortho_chart(16.0, 16.0, 64.0, 0.52)),
        (
            "wall",
            wall_chart(24, [20.0, 76.0, 20.0, 76.0], 60.0, 3.0, 0.0, 0.4),
        ),
    ] {
        let exact = run(&chart, &img, opts(Mode::Exact, 40));
        let rmse: Vec<f64> = [1, 2, 4, 8, 16]
            .iter()
            .map(|&n| rmse_known(&run(&chart, &img, opts(Mode::Subtexel(n), 40)), &exact))
            .collect();
        let bil = rmse_known(&run(&chart, &img, opts(Mode::Bilinear, 40)), &exact);
        for k in 1..rmse.len() {
            assert!(
                rmse[k] < rmse[k - 1],
                "{name}: RMSE not decreasing in N: {rmse:?}"
            );
        }
        assert!(
            rmse[4] < 1.0 && bil > rmse[0],
            "{name}: {rmse:?}, bilinear {bil}"
        );
    }
}

#[test]
// indexed loops: each index serves more than one array or lookup
#[allow(clippy::needless_range_loop)]
fn orthographic_chart_is_area_average_downsampling() {
    let img = random_image(60, 60, 3);
    // chart = the whole image; texel = block of 3x3 pixels, or 1.5 x 1.5 pixels
    let chart = ortho_chart(0.0, 0.0, 60.0, 0.0);
    for texels in [20u32, 40, 60] {
        let s = 60.0 / texels as f64;
        for mode in [
            Mode::Exact,
            Mode::Subtexel(1),
            Mode::Subtexel(3),
            Mode::Subtexel(8),
        ] {
            let r = run(&chart, &img, opts(mode, texels));
            assert_eq!(r.stats.known_texels, (texels * texels) as usize);
            assert_eq!(r.stats.bilinear_fallbacks, 0);
            for j in 0..texels {
                for i in 0..texels {
                    // separable box overlaps of the texel [i*s, (i+1)*s] with pixel [c, c+1]
                    let ov = |t: u32, p: u32| {
                        let (a, b) = (t as f64 * s, (t + 1) as f64 * s);
                        (b.min(p as f64 + 1.0) - a.max(p as f64)).max(0.0)
                    };
                    let mut want = [0.0; 3];
                    for r in 0..60 {
                        for c in 0..60 {
                            let w = ov(i, c) * ov(j, r) / (s * s);
                            if w > 0.0 {
                                for k in 0..3 {
                                    want[k] += w * img.get_pixel(c, r)[k] as f64;
                                }
                            }
                        }
                    }
                    let got = r.image.get_pixel(i, j);
                    for k in 0..3 {
                        assert!(
                            (got[k] as f64 - want[k]).abs() <= 0.5 + 1e-6,
                            "{mode:?} {texels}: ({i},{j}) {} vs {}",
                            got[k],
                            want[k]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn output_is_independent_of_thread_count() {
    let img = random_image(64, 64, 5);
    let chart = wall_chart(20, [8.0, 56.0, 8.0, 56.0], 60.0, 1.5, 0.1, 0.3);
    for mode in [Mode::Subtexel(4), Mode::Exact, Mode::Bilinear] {
        let o = ResampleOptions {
            mode,
            texels: 96,
            fill: Fill::PullPush,
            gutter_texels: 2,
        };
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| e.to_string())
        };
        let (Ok(p1), Ok(p2)) = (pool(1), pool(2)) else {
            panic!("no thread pool")
        };
        let a = p1.install(|| run(&chart, &img, o));
        let b = p2.install(|| run(&chart, &img, o));
        assert_eq!(a.image.as_raw(), b.image.as_raw());
        assert_eq!(a.stats, b.stats);
    }
}

mod common;

#[test]
fn engabreen_ortho_cell_is_block_averaged_and_walls_resample_cleanly() {
    let path = common::real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let img = match image::open(&path) {
        Ok(i) => i.to_rgba8(),
        Err(e) => panic!("{}: {e}", path.display()),
    };
    assert_eq!((img.width(), img.height()), (507, 590));
    let georef = GridGeoref::new(445302.17, 7396769.45, 3.0);
    // a cell whose square spans pixels [c0, c0 + 96) x [r0, r0 + 96) edge to edge, in a
    // cell-local frame centred on the square
    let (c0, r0) = (300u32, 200u32);
    let (x_min, y_max) = georef.world(r0 as f64 - 0.5, c0 as f64 - 0.5);
    let centre = [x_min + 144.0, y_max - 144.0];
    let chart = ortho_chart(-144.0, -144.0, 288.0, 0.0);
    let src = Source {
        image: &img,
        to_pixel: PixelMap::from_georef(&georef, centre),
    };
    for mode in [Mode::Exact, Mode::Subtexel(4)] {
        let o = ResampleOptions {
            mode,
            texels: 32,
            fill: Fill::PullPush,
            gutter_texels: 0,
        };
        let r = match resample(&chart.mesh(), &src, &o) {
            Ok(r) => r,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(r.stats.known_texels, 32 * 32);
        for j in 0..32 {
            for i in 0..32 {
                let mut want = [0.0; 3];
                for dr in 0..3 {
                    for dc in 0..3 {
                        let p = img.get_pixel(c0 + 3 * i + dc, r0 + 3 * j + dr);
                        for k in 0..3 {
                            want[k] += p[k] as f64 / 9.0;
                        }
                    }
                }
                let got = r.image.get_pixel(i, j);
                for k in 0..3 {
                    assert!(
                        (got[k] as f64 - want[k]).abs() <= 0.5 + 1e-6,
                        "{mode:?} ({i},{j}) ch {k}"
                    );
                }
            }
        }
    }
    // a steep wall chart over the real ortho: subtexel N = 8 close to exact
    let wall = wall_chart(32, [-90.0, 90.0, -90.0, 90.0], 300.0, 6.0, 0.0, 0.7);
    let run_mode = |mode| match resample(&wall.mesh(), &src, &opts(mode, 128)) {
        Ok(r) => r,
        Err(e) => panic!("{e}"),
    };
    let exact = run_mode(Mode::Exact);
    check_consistency(&exact);
    assert!(
        exact.stats.bilinear_fallbacks > 0
            && exact.stats.known_texels == exact.stats.covered_texels
    );
    assert!(rmse_known(&run_mode(Mode::Subtexel(8)), &exact) < 2.55);
}
