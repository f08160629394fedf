//! The lit export variant: per-vertex normals and tangents of a cell, and its normal map
//! baked into tangent space (docs/export.md, "Lit variant").
//!
//! The store's normal maps hold unit normals in the cell's frame (the CRS's x east, y north,
//! z up; `n·0.5 + 0.5` in RGB). glTF wants a tangent-space map: per texel the normal in the
//! frame `(T, B, N)` a viewer interpolates from the vertices' `TANGENT` and `NORMAL`, with
//! `B = cross(N, T) · w` (glTF 2.0, "Meshes"). [`vertex_frames`] gives those vertex frames
//! (area-weighted face normals; tangents along `∂P/∂u`, Gram-Schmidt against the normal;
//! `w` so that `B` points along `−∂P/∂v`, towards the top of the image, glTF's "+Y up" for
//! normal textures), and [`bake_tangent_normals`] expresses every texel's stored normal in
//! the frame interpolated at its centre. The frame computed from the exported (projected)
//! positions differs from the store's by the local rotation of the map to the export frame
//! (a conformal projection: rotation and scale), under which tangent-space coordinates do
//! not change, so the viewer's `T·x + B·y + N·z` gives back the stored normal in its frame.

use glam::DVec3;
use image::RgbImage;

/// Per vertex: unit normal and tangent `(x, y, z, w)` (unit `xyz` ⟂ normal, `w = ±1`).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexFrames {
    /// Unit normals (up, `+z`, for vertices of no triangle with area).
    pub normals: Vec<DVec3>,
    /// Unit tangents with the handedness `w` of the bitangent `cross(N, T)·w`.
    pub tangents: Vec<[f64; 4]>,
}

/// The normals and tangents of the vertices `positions` (any right-handed frame) with
/// texture coordinates `uvs` (u right, v down) over the triangles `tris` (counter-clockwise
/// seen from the side the normals point to); see the [module docs](self).
pub fn vertex_frames(positions: &[DVec3], uvs: &[[f32; 2]], tris: &[[u32; 3]]) -> VertexFrames {
    let n = positions.len();
    let (mut nsum, mut usum, mut vsum) = (
        vec![DVec3::ZERO; n],
        vec![DVec3::ZERO; n],
        vec![DVec3::ZERO; n],
    );
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        if a >= n || b >= n || c >= n || a >= uvs.len() || b >= uvs.len() || c >= uvs.len() {
            continue;
        }
        let (e1, e2) = (positions[b] - positions[a], positions[c] - positions[a]);
        let face = e1.cross(e2); // |face| = twice the area
        let uv = |i: usize| [uvs[i][0] as f64, uvs[i][1] as f64];
        let (ua, ub, uc) = (uv(a), uv(b), uv(c));
        let (du1, dv1, du2, dv2) = (ub[0] - ua[0], ub[1] - ua[1], uc[0] - ua[0], uc[1] - ua[1]);
        let r = du1 * dv2 - du2 * dv1;
        // ∂P/∂u and ∂P/∂v of the triangle, weighted by its area (|r|/2 of UV area scales
        // them by 1/|r|: multiply back by the triangle's area over its UV area)
        let (dpdu, dpdv) = if r.abs() > 1e-20 {
            (((e1 * dv2 - e2 * dv1) / r), ((e2 * du1 - e1 * du2) / r))
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let w = face.length();
        let (su, sv) = (dpdu.normalize_or_zero() * w, dpdv.normalize_or_zero() * w);
        for i in [a, b, c] {
            nsum[i] += face;
            usum[i] += su;
            vsum[i] += sv;
        }
    }
    let mut normals = Vec::with_capacity(n);
    let mut tangents = Vec::with_capacity(n);
    for i in 0..n {
        let nn = nsum[i].try_normalize().unwrap_or(DVec3::Z);
        let t = (usum[i] - nn * nn.dot(usum[i]))
            .try_normalize()
            .or_else(|| (DVec3::X - nn * nn.x).try_normalize())
            .or_else(|| (DVec3::Y - nn * nn.y).try_normalize())
            .unwrap_or(DVec3::X);
        let w = if nn.cross(t).dot(-vsum[i]) < 0.0 {
            -1.0
        } else {
            1.0
        };
        normals.push(nn);
        tangents.push([t.x, t.y, t.z, w]);
    }
    VertexFrames { normals, tangents }
}

/// The object-space normal map `normal_map` (the cell's frame, `n·0.5 + 0.5`) in the
/// tangent space of `frames` (from [`vertex_frames`] of the same vertices, texture
/// coordinates and triangles): per texel whose centre lies in a triangle (in texture space),
/// `(n·T, n·B, n·N)·0.5 + 0.5` with the frame interpolated at the centre; other texels
/// (gutters) `(0.5, 0.5, 1)`, the interpolated normal itself. Same size as `normal_map`.
pub fn bake_tangent_normals(
    normal_map: &RgbImage,
    uvs: &[[f32; 2]],
    tris: &[[u32; 3]],
    frames: &VertexFrames,
) -> RgbImage {
    let (w, h) = normal_map.dimensions();
    let mut out = RgbImage::from_pixel(w, h, image::Rgb([128, 128, 255]));
    let nv = frames
        .normals
        .len()
        .min(frames.tangents.len())
        .min(uvs.len());
    for t in tris {
        let [a, b, c] = t.map(|i| i as usize);
        if a >= nv || b >= nv || c >= nv {
            continue;
        }
        // texel-centre coordinates: texel (i, j) has its centre at (i + 0.5, j + 0.5)
        let p = |i: usize| [uvs[i][0] as f64 * w as f64, uvs[i][1] as f64 * h as f64];
        let (pa, pb, pc) = (p(a), p(b), p(c));
        let det = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pc[0] - pa[0]) * (pb[1] - pa[1]);
        if !(det.abs() > 1e-12) {
            continue;
        }
        let lo = |k: usize| pa[k].min(pb[k]).min(pc[k]);
        let hi = |k: usize| pa[k].max(pb[k]).max(pc[k]);
        let x0 = (lo(0) - 0.5).ceil().max(0.0) as u32;
        let x1 = ((hi(0) - 0.5).floor().min(w as f64 - 1.0)).max(-1.0) as i64;
        let y0 = (lo(1) - 0.5).ceil().max(0.0) as u32;
        let y1 = ((hi(1) - 0.5).floor().min(h as f64 - 1.0)).max(-1.0) as i64;
        for y in y0 as i64..=y1 {
            for x in x0 as i64..=x1 {
                let q = [x as f64 + 0.5, y as f64 + 0.5];
                let l1 =
                    ((q[0] - pa[0]) * (pc[1] - pa[1]) - (pc[0] - pa[0]) * (q[1] - pa[1])) / det;
                let l2 =
                    ((pb[0] - pa[0]) * (q[1] - pa[1]) - (q[0] - pa[0]) * (pb[1] - pa[1])) / det;
                let l0 = 1.0 - l1 - l2;
                const EPS: f64 = -1e-9;
                if l0 < EPS || l1 < EPS || l2 < EPS {
                    continue;
                }
                let lerp = |f: &dyn Fn(usize) -> DVec3| f(a) * l0 + f(b) * l1 + f(c) * l2;
                let nn = lerp(&|i| frames.normals[i])
                    .try_normalize()
                    .unwrap_or(DVec3::Z);
                let tv = lerp(&|i| {
                    DVec3::new(
                        frames.tangents[i][0],
                        frames.tangents[i][1],
                        frames.tangents[i][2],
                    )
                });
                let tt = (tv - nn * nn.dot(tv))
                    .try_normalize()
                    .unwrap_or_else(|| nn.any_orthonormal_vector());
                let hand = frames.tangents[a][3] * l0
                    + frames.tangents[b][3] * l1
                    + frames.tangents[c][3] * l2;
                let bb = nn.cross(tt) * if hand < 0.0 { -1.0 } else { 1.0 };
                let px = normal_map.get_pixel(x as u32, y as u32).0;
                let s = DVec3::new(
                    px[0] as f64 / 127.5 - 1.0,
                    px[1] as f64 / 127.5 - 1.0,
                    px[2] as f64 / 127.5 - 1.0,
                )
                .try_normalize()
                .unwrap_or(nn);
                let ts = [s.dot(tt), s.dot(bb), s.dot(nn)];
                out.put_pixel(
                    x as u32,
                    y as u32,
                    image::Rgb(
                        ts.map(|v| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0).round() as u8),
                    ),
                );
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of `k × k` quads over a plane `z = gx·x + gy·y`, texture coordinates from x, y
    /// (v down: north up in the image), counter-clockwise from above.
    fn plane(k: usize, gx: f64, gy: f64) -> (Vec<DVec3>, Vec<[f32; 2]>, Vec<[u32; 3]>) {
        let (mut p, mut uv, mut t) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..=k {
            for i in 0..=k {
                let (x, y) = (i as f64, j as f64);
                p.push(DVec3::new(x, y, gx * x + gy * y));
                uv.push([(x / k as f64) as f32, (1.0 - y / k as f64) as f32]);
            }
        }
        let v = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                t.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                t.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        (p, uv, t)
    }

    fn encode(n: DVec3) -> image::Rgb<u8> {
        image::Rgb(
            n.to_array()
                .map(|v| ((v * 0.5 + 0.5) * 255.0).round() as u8),
        )
    }

    fn decode(p: image::Rgb<u8>) -> DVec3 {
        DVec3::new(
            p.0[0] as f64 / 127.5 - 1.0,
            p.0[1] as f64 / 127.5 - 1.0,
            p.0[2] as f64 / 127.5 - 1.0,
        )
    }

    #[test]
    fn frames_of_a_tilted_plane() {
        let (p, uv, t) = plane(4, 0.5, -0.25);
        let f = vertex_frames(&p, &uv, &t);
        let want = DVec3::new(-0.5, 0.25, 1.0).normalize();
        for (n, tg) in f.normals.iter().zip(&f.tangents) {
            assert!((*n - want).length() < 1e-12, "{n}");
            let tv = DVec3::new(tg[0], tg[1], tg[2]);
            assert!(tv.dot(*n).abs() < 1e-12 && (tv.length() - 1.0).abs() < 1e-12);
            // u runs east: the tangent is the plane's direction over +x
            assert!(
                (tv - DVec3::new(1.0, 0.0, 0.5).normalize()).length() < 1e-12,
                "{tv}"
            );
            // B = cross(N, T)·w points to decreasing v, north over the plane here
            let b = n.cross(tv) * tg[3];
            assert!(b.dot(DVec3::new(0.0, 1.0, -0.25)) > 0.9, "{b} w {}", tg[3]);
        }
    }

    #[test]
    fn the_stored_normal_comes_back_through_the_tangent_frame() {
        // a curved surface (a bump) with a normal map of its own normals perturbed by a
        // pattern: T·x + B·y + N·z of the baked texel, with the frame a viewer interpolates,
        // is the stored normal (to the 8-bit encoding)
        let k = 8;
        let (mut p, uv, t) = plane(k, 0.0, 0.0);
        for q in p.iter_mut() {
            q.z = 0.3 * ((q.x - 4.0).powi(2) + (q.y - 4.0).powi(2)).sqrt().cos() * 2.0;
        }
        let f = vertex_frames(&p, &uv, &t);
        let size = 64u32;
        let stored = RgbImage::from_fn(size, size, |x, y| {
            let a = x as f64 * 0.3;
            let b = y as f64 * 0.2;
            encode(DVec3::new(0.4 * a.sin(), 0.3 * b.cos(), 1.0).normalize())
        });
        let baked = bake_tangent_normals(&stored, &uv, &t, &f);
        let mut checked = 0;
        for ti in &t {
            let [a, b, c] = ti.map(|i| i as usize);
            // the triangle's centroid texel
            let cu = (uv[a][0] + uv[b][0] + uv[c][0]) as f64 / 3.0;
            let cv = (uv[a][1] + uv[b][1] + uv[c][1]) as f64 / 3.0;
            let (x, y) = ((cu * size as f64) as u32, (cv * size as f64) as u32);
            let q = [x as f64 + 0.5, y as f64 + 0.5];
            // barycentrics of the texel centre, as the bake computes them
            let pp = |i: usize| [uv[i][0] as f64 * size as f64, uv[i][1] as f64 * size as f64];
            let (pa, pb, pc) = (pp(a), pp(b), pp(c));
            let det = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pc[0] - pa[0]) * (pb[1] - pa[1]);
            let l1 = ((q[0] - pa[0]) * (pc[1] - pa[1]) - (pc[0] - pa[0]) * (q[1] - pa[1])) / det;
            let l2 = ((pb[0] - pa[0]) * (q[1] - pa[1]) - (q[0] - pa[0]) * (pb[1] - pa[1])) / det;
            let l0 = 1.0 - l1 - l2;
            if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                continue;
            }
            // what a viewer does: interpolate, normalise, B = cross(N, T)·w
            let n = (f.normals[a] * l0 + f.normals[b] * l1 + f.normals[c] * l2).normalize();
            let tv = |i: usize| DVec3::new(f.tangents[i][0], f.tangents[i][1], f.tangents[i][2]);
            let tt = tv(a) * l0 + tv(b) * l1 + tv(c) * l2;
            let tt = (tt - n * n.dot(tt)).normalize();
            let bb = n.cross(tt) * f.tangents[a][3];
            let m = decode(*baked.get_pixel(x, y));
            let back = (tt * m.x + bb * m.y + n * m.z).normalize();
            let want = decode(*stored.get_pixel(x, y)).normalize();
            assert!(
                back.angle_between(want).to_degrees() < 1.0,
                "texel {x},{y}: {back} vs {want}"
            );
            checked += 1;
        }
        assert!(checked > 50, "{checked}");
        // a flat surface whose stored normals are its own: (0.5, 0.5, 1) everywhere
        let (p, uv, t) = plane(4, 0.0, 0.0);
        let f = vertex_frames(&p, &uv, &t);
        let flat = RgbImage::from_pixel(16, 16, encode(DVec3::Z));
        let baked = bake_tangent_normals(&flat, &uv, &t, &f);
        assert!(
            baked.pixels().all(|p| p.0 == [128, 128, 255]),
            "{:?}",
            baked.get_pixel(3, 3)
        );
    }

    #[test]
    fn degenerate_input_gives_finite_frames() {
        let p = vec![
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(f64::NAN, 0.0, 0.0),
        ];
        let uv = vec![[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.5, 0.5]];
        let f = vertex_frames(&p, &uv, &[[0, 1, 2], [0, 2, 9]]);
        for (n, t) in f.normals.iter().zip(&f.tangents) {
            assert!(
                n.is_finite() && t.iter().all(|v| v.is_finite()),
                "{n} {t:?}"
            );
        }
        let img = bake_tangent_normals(&RgbImage::new(4, 4), &uv, &[[0, 1, 2], [7, 8, 9]], &f);
        assert_eq!(img.dimensions(), (4, 4));
    }
}
