// cliffmap terrain shader: one draw per quadtree cell.
// Positions are cell-local f32 metres; `draw.mvp` already contains the f64-computed offset of
// the cell origin from the camera, so world magnitudes never reach the GPU.

struct Frame {
    // World direction towards the sun (unit), w unused.
    sun_dir: vec4<f32>,
    // x: 1 = lit, 0 = unlit; y: ambient fraction in lit mode; z: 1 = level colouring overlay.
    params: vec4<f32>,
};

struct Draw {
    mvp: mat4x4<f32>,
    // (min_x - origin_x, max_y - origin_y, width, height) of the cell's nominal square, metres.
    extent: vec4<f32>,
    // Overlay colour of the cell's level (linear RGB).
    tint: vec4<f32>,
    // Geomorphing: x = morph factor t in [0, 1] (0: as stored, 1: the parent's shape and
    // textures); w = 1 if the parent's textures are bound (group 2), else y / z = LOD shift of
    // the colour texture / normal map to the parent's texel density, mip levels (fallback).
    morph: vec4<f32>,
    // Relief mapping: x = range of the relief map, metres (0: off); yzw = the eye, cell-local.
    relief: vec4<f32>,
    // x = smallest up component of a relief-mapped triangle's unit normal; y = 1 if texture
    // coordinates come from a vertex stream (the lookup then moves through the triangle's
    // own map from (x, y) to texture coordinates), 0 if they are orthographic (planar_uv);
    // z = 1 if the colour texture's alpha is the share of base_tex in each texel (a chart
    // drawn with its photo texture: only that share moves), else 0; w = 1 if ortho_tex holds
    // the chart's orthographic texture, else 0.
    relief_limits: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> draw: Draw;
@group(1) @binding(0) var colour_tex: texture_2d<f32>;
@group(1) @binding(1) var normal_tex: texture_2d<f32>;
@group(1) @binding(2) var samp: sampler;
// The relief map (R8: the DEM's height above the TIN, encoded over ±draw.relief.x metres), in
// the orthographic layout of the nominal square whatever the colour texture's layout.
@group(1) @binding(3) var relief_tex: texture_2d<f32>;
// A photo-textured chart's own (reparameterized) texture: its share of each photo texel (the
// photo texture's alpha) is relief-mapped; a placeholder elsewhere.
@group(1) @binding(4) var base_tex: texture_2d<f32>;
// A chart's orthographic texture (its cell's texture before reparameterization), read where it
// resolves the surface more finely than the chart; a placeholder elsewhere.
@group(1) @binding(5) var ortho_tex: texture_2d<f32>;
// The parent cell's textures (placeholders unless morphing with a resident parent).
@group(2) @binding(0) var parent_colour: texture_2d<f32>;
@group(2) @binding(1) var parent_normal: texture_2d<f32>;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
    // The parent's texture coordinates of the same surface point (geomorphing only).
    @location(1) puv: vec2<f32>,
    // The drawn surface point, cell-local metres (relief mapping).
    @location(2) lp: vec3<f32>,
    // Longest relief shift, metres (cells/relief_reach.rs; charts only, else unbounded).
    @location(3) reach: f32,
};

// The reach of orthographic texture coordinates: unbounded (the layout is continuous).
const NO_REACH: f32 = 1.0e9;

// Orthographic texture coordinates of a cell-local point: u east, v south over the nominal square.
fn planar_uv(p: vec2<f32>) -> vec2<f32> {
    return vec2<f32>((p.x - draw.extent.x) / draw.extent.z, (draw.extent.y - p.y) / draw.extent.w);
}

// Orthographic cells.
@vertex
fn vs_ortho(@location(0) p: vec3<f32>) -> VOut {
    var o: VOut;
    o.pos = draw.mvp * vec4<f32>(p, 1.0);
    o.uv = planar_uv(p.xy);
    o.puv = o.uv;
    o.lp = p;
    o.reach = NO_REACH;
    return o;
}

// Cells with stored texture coordinates (reparameterized charts): `uvr.xy` the coordinates,
// `uvr.z` the vertex's relief reach.
@vertex
fn vs_uv(@location(0) p: vec3<f32>, @location(1) uvr: vec3<f32>) -> VOut {
    var o: VOut;
    o.pos = draw.mvp * vec4<f32>(p, 1.0);
    o.uv = uvr.xy;
    o.puv = uvr.xy;
    o.lp = p;
    o.reach = uvr.z;
    return o;
}

// Geomorphed variants: the height moves to the parent's surface height `m.x` by the factor t;
// `m.yz` are the parent's texture coordinates of the same point.
@vertex
fn vs_ortho_morph(@location(0) p: vec3<f32>, @location(2) m: vec3<f32>) -> VOut {
    var o: VOut;
    let q = vec3<f32>(p.xy, mix(p.z, m.x, draw.morph.x));
    o.pos = draw.mvp * vec4<f32>(q, 1.0);
    o.uv = planar_uv(p.xy);
    o.puv = m.yz;
    o.lp = q;
    o.reach = NO_REACH;
    return o;
}

@vertex
fn vs_uv_morph(@location(0) p: vec3<f32>, @location(1) uvr: vec3<f32>, @location(2) m: vec3<f32>) -> VOut {
    var o: VOut;
    let q = vec3<f32>(p.xy, mix(p.z, m.x, draw.morph.x));
    o.pos = draw.mvp * vec4<f32>(q, 1.0);
    o.uv = uvr.xy;
    o.puv = m.yz;
    o.lp = q;
    o.reach = uvr.z;
    return o;
}

// Gradient scale that moves a texture's level of detail from its own `lod` to
// mix(lod, max(lod, shift), t): where the texture is finer than the parent's (lod < shift),
// the sample blends towards the parent's texel density. `g` are the uv derivatives.
fn morph_grad_scale(gx: vec2<f32>, gy: vec2<f32>, size: vec2<f32>, shift: f32, t: f32) -> f32 {
    let a = gx * size;
    let b = gy * size;
    let la = dot(a, a);
    let lb = dot(b, b);
    let major = sqrt(max(la, lb));
    let minor = sqrt(min(la, lb));
    // The level anisotropic filtering (8 taps at most) samples at.
    let taps = clamp(ceil(major / max(minor, 1e-20)), 1.0, 8.0);
    let lod = log2(max(major / taps, 1e-20));
    return exp2(t * max(shift - lod, 0.0));
}

// The relief map's height (metres above the TIN) at cell-local point `p`.
fn relief_at(p: vec2<f32>, range: f32) -> f32 {
    // bilinear between texel centres by hand: four loads (cheaper than a filtered sample
    // under software rasterizers, whose sampler is anisotropic)
    let size = vec2<i32>(textureDimensions(relief_tex, 0));
    let x = planar_uv(p) * vec2<f32>(size) - vec2<f32>(0.5);
    let x0 = floor(x);
    let w = x - x0;
    let hi = size - vec2<i32>(1);
    let i0 = clamp(vec2<i32>(x0), vec2<i32>(0), hi);
    let i1 = clamp(vec2<i32>(x0) + vec2<i32>(1), vec2<i32>(0), hi);
    let a00 = textureLoad(relief_tex, i0, 0).r;
    let a10 = textureLoad(relief_tex, vec2<i32>(i1.x, i0.y), 0).r;
    let a01 = textureLoad(relief_tex, vec2<i32>(i0.x, i1.y), 0).r;
    let a11 = textureLoad(relief_tex, i1, 0).r;
    let v = mix(mix(a00, a10, w.x), mix(a01, a11, w.x), w.y);
    return (v * 2.0 - 1.0) * range;
}

// Relief mapping: how far, in cell-local (x, y) metres, the point where the ray from the eye
// through the drawn point `lp` (on the TIN triangle of unit upward normal `n`) meets the
// surface "TIN plane + relief" lies from `lp`: the relief map (the DEM's height above the
// TIN, within ±`range` metres) searched between the ray's heights +range and −range above the
// triangle's plane in steps of about 4 texels, the first crossing refined by false position.
// Triangles steeper than the cell's limit, rays along the plane and fragments where the hit
// can move less than a quarter of the pixel's `footprint` (metres) give (0, 0).
// photo/relief.rs (CellRelief::shift) is the same search on the CPU: the projection puts a
// photo's colour where this lookup finds it.
fn relief_shift(lp: vec3<f32>, n: vec3<f32>, range: f32, footprint: f32) -> vec2<f32> {
    let none = vec2<f32>(0.0);
    let d = lp - draw.relief.yzw;
    // height above the plane gained per unit of s along p(s) = lp + s·d (s = 0 at lp)
    let k = dot(d, n) / max(n.z, 1e-6);
    if n.z < draw.relief_limits.x || k > -1e-4 * length(d) {
        return none;
    }
    let s0 = range / k;
    let s1 = -range / k;
    // The hit moves at most half the search's ground span from lp: skip what no pixel shows.
    let ground_span = abs(s1 - s0) * length(d.xy);
    if 0.5 * ground_span < 0.25 * footprint {
        return none;
    }
    // A coarse search (steps of about 4 texels of the relief map, at most 8) brackets the
    // first crossing; two false-position steps inside the bracket refine it.
    let size = vec2<f32>(textureDimensions(relief_tex, 0));
    let span = abs(s1 - s0) * length(d.xy / draw.extent.zw * size);
    // Far beyond the drawn triangle the TIN bends away from its plane: searches longer than
    // 48 texels of the relief map (very grazing rays) are left out (docs/rendering.md).
    if span > 48.0 {
        return none;
    }
    let steps = i32(clamp(ceil(span / 4.0), 1.0, 8.0));
    var a = s0;
    var fa = 0.0;
    var b = s1;
    var fb = -1.0;
    for (var j = 0; j <= steps; j = j + 1) {
        let s = mix(s0, s1, f32(j) / f32(steps));
        let f = s * k - relief_at(lp.xy + s * d.xy, range);
        if f <= 0.0 {
            b = s;
            fb = f;
            break;
        }
        a = s;
        fa = f;
    }
    var hit = b;
    if fa > 0.0 {
        for (var j = 0; j < 2; j = j + 1) {
            let s = a + (b - a) * fa / max(fa - fb, 1e-12);
            let f = s * k - relief_at(lp.xy + s * d.xy, range);
            if f > 0.0 {
                a = s;
                fa = f;
            } else {
                b = s;
                fb = f;
            }
        }
        hit = a + (b - a) * fa / max(fa - fb, 1e-12);
    }
    return hit * d.xy;
}

// The texture coordinates of the drawn point `lp` (texture coordinates `uv`, screen
// derivatives `gx`, `gy` of uv and `px`, `py` of lp) moved by `shift` metres in (x, y):
// orthographic cells through planar_uv; vertex-stream cells through the triangle's affine map
// from (x, y) to uv, `[gx gy] · [px.xy py.xy]⁻¹` (the projection's texel_shift), kept as
// they are where the triangle is edge-on in (x, y).
fn shifted_uv(lp: vec3<f32>, uv: vec2<f32>, shift: vec2<f32>, gx: vec2<f32>, gy: vec2<f32>,
              px: vec3<f32>, py: vec3<f32>) -> vec2<f32> {
    if draw.relief_limits.y < 0.5 {
        return planar_uv(lp.xy + shift);
    }
    let det = px.x * py.y - py.x * px.y;
    let scale = max(dot(px.xy, px.xy), dot(py.xy, py.xy));
    if !(abs(det) > 1e-6 * scale) {
        return uv;
    }
    // shift = a·px.xy + b·py.xy; uv moves by a·gx + b·gy
    let a = (shift.x * py.y - py.x * shift.y) / det;
    let b = (px.x * shift.y - shift.x * px.y) / det;
    return uv + a * gx + b * gy;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    var c: vec4<f32>;
    var n_raw: vec3<f32>;
    let t = draw.morph.x;
    // Derivatives first (uniform control flow): texture coordinates, the triangle's normal.
    let gx = dpdx(i.uv);
    let gy = dpdy(i.uv);
    let px = dpdx(i.lp);
    let py = dpdy(i.lp);
    var nf = cross(px, py);
    if nf.z < 0.0 {
        nf = -nf;
    }
    let range = draw.relief.x * (1.0 - t);
    var uv = i.uv;
    // the relief move, unbounded by the chart's reach (for orthographic lookups)
    var oshift = vec2<f32>(0.0);
    if range > 0.0 && dot(nf, nf) > 0.0 {
        var shift = relief_shift(i.lp, normalize(nf), range, max(length(px), length(py)));
        oshift = shift;
        // on charts, only within the reach (the triangle's map holds that far); a longer
        // move is dropped, as the projection drops it (a shortened one would be neither the
        // relief surface's point nor the TIN's)
        if length(shift) > i.reach {
            shift = vec2<f32>(0.0);
        }
        uv = shifted_uv(i.lp, i.uv, shift, gx, gy, px, py);
    }
    if t > 0.0 && draw.morph.w > 0.5 {
        // Blend towards the parent's textures at the same surface point.
        let cc = textureSampleGrad(colour_tex, samp, uv, gx, gy);
        let cp = textureSample(parent_colour, samp, i.puv);
        c = mix(cc, cp, t);
        let nc = textureSampleGrad(normal_tex, samp, uv, gx, gy).xyz;
        let np = textureSample(parent_normal, samp, i.puv).xyz;
        n_raw = mix(nc, np, t) * 2.0 - vec3<f32>(1.0);
    } else if t > 0.0 {
        // Parent not resident: the cell's own textures at up to the parent's texel density.
        let sc = morph_grad_scale(gx, gy, vec2<f32>(textureDimensions(colour_tex, 0)), draw.morph.y, t);
        let sn = morph_grad_scale(gx, gy, vec2<f32>(textureDimensions(normal_tex, 0)), draw.morph.z, t);
        c = textureSampleGrad(colour_tex, samp, uv, gx * sc, gy * sc);
        n_raw = textureSampleGrad(normal_tex, samp, uv, gx * sn, gy * sn).xyz * 2.0 - vec3<f32>(1.0);
    } else if range > 0.0 {
        // Lookups relief mapping leaves in place sample with implicit derivatives, as
        // without relief mapping: explicit ones read a coarse mip at silhouette fragments
        // (lavapipe; single pixels of a texture's mean colour along walls' edges).
        c = textureSample(colour_tex, samp, i.uv);
        var nt = textureSample(normal_tex, samp, i.uv);
        let moved = any(uv != i.uv);
        // On a chart, the orthographic texture where it has more texels per pixel than the
        // chart (flat ground, which a chart gives fewer texels than the orthophoto has).
        let ogx = vec2<f32>(px.x / draw.extent.z, -px.y / draw.extent.w);
        let ogy = vec2<f32>(py.x / draw.extent.z, -py.y / draw.extent.w);
        var cdim = vec2<f32>(textureDimensions(colour_tex, 0));
        if draw.relief_limits.z > 0.5 {
            cdim = vec2<f32>(textureDimensions(base_tex, 0));
        }
        let odim = vec2<f32>(textureDimensions(ortho_tex, 0));
        let chart_density = abs(gx.x * gy.y - gx.y * gy.x) * cdim.x * cdim.y;
        let ortho_density = abs(ogx.x * ogy.y - ogx.y * ogy.x) * odim.x * odim.y;
        let use_ortho = draw.relief_limits.w > 0.5 && ortho_density >= chart_density;
        var o = textureSample(ortho_tex, samp, planar_uv(i.lp.xy));
        if use_ortho && any(oshift != vec2<f32>(0.0)) {
            o = textureSampleGrad(ortho_tex, samp, planar_uv(i.lp.xy + oshift), ogx, ogy);
        }
        if draw.relief_limits.z > 0.5 {
            // A chart drawn with its photo texture: the photo's colour stays where the
            // projection put it; the chart texture's share of the texel (alpha) moves.
            let b0 = textureSample(base_tex, samp, i.uv);
            var b1 = b0;
            if use_ortho {
                b1 = o;
            } else if moved {
                b1 = textureSampleGrad(base_tex, samp, uv, gx, gy);
            }
            c = vec4<f32>(clamp(c.rgb + c.a * (b1.rgb - b0.rgb), vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
        } else if use_ortho {
            c = o;
        } else if moved {
            c = textureSampleGrad(colour_tex, samp, uv, gx, gy);
        }
        if moved {
            nt = textureSampleGrad(normal_tex, samp, uv, gx, gy);
        }
        n_raw = nt.xyz * 2.0 - vec3<f32>(1.0);
    } else {
        c = textureSample(colour_tex, samp, i.uv);
        n_raw = textureSample(normal_tex, samp, i.uv).xyz * 2.0 - vec3<f32>(1.0);
    }
    var rgb = c.rgb;
    if frame.params.z > 0.5 {
        rgb = mix(rgb, draw.tint.rgb, 0.5);
    }
    if frame.params.x > 0.5 {
        let n = normalize(n_raw);
        let d = max(dot(n, frame.sun_dir.xyz), 0.0);
        rgb = rgb * (frame.params.y + (1.0 - frame.params.y) * d);
    }
    return vec4<f32>(rgb, 1.0);
}

// Bounding-box lines of the level overlay: the level colour, unlit.
@fragment
fn fs_line(i: VOut) -> @location(0) vec4<f32> {
    return vec4<f32>(draw.tint.rgb, 1.0);
}
