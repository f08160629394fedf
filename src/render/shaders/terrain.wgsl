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
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> draw: Draw;
@group(1) @binding(0) var colour_tex: texture_2d<f32>;
@group(1) @binding(1) var normal_tex: texture_2d<f32>;
@group(1) @binding(2) var samp: sampler;
// The parent cell's textures (placeholders unless morphing with a resident parent).
@group(2) @binding(0) var parent_colour: texture_2d<f32>;
@group(2) @binding(1) var parent_normal: texture_2d<f32>;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
    // The parent's texture coordinates of the same surface point (geomorphing only).
    @location(1) puv: vec2<f32>,
};

// Orthographic cells: u east, v south over the nominal square.
@vertex
fn vs_ortho(@location(0) p: vec3<f32>) -> VOut {
    var o: VOut;
    o.pos = draw.mvp * vec4<f32>(p, 1.0);
    o.uv = vec2<f32>((p.x - draw.extent.x) / draw.extent.z, (draw.extent.y - p.y) / draw.extent.w);
    o.puv = o.uv;
    return o;
}

// Cells with stored texture coordinates (reparameterized charts).
@vertex
fn vs_uv(@location(0) p: vec3<f32>, @location(1) uv: vec2<f32>) -> VOut {
    var o: VOut;
    o.pos = draw.mvp * vec4<f32>(p, 1.0);
    o.uv = uv;
    o.puv = uv;
    return o;
}

// Geomorphed variants: the height moves to the parent's surface height `m.x` by the factor t;
// `m.yz` are the parent's texture coordinates of the same point.
@vertex
fn vs_ortho_morph(@location(0) p: vec3<f32>, @location(2) m: vec3<f32>) -> VOut {
    var o: VOut;
    let q = vec3<f32>(p.xy, mix(p.z, m.x, draw.morph.x));
    o.pos = draw.mvp * vec4<f32>(q, 1.0);
    o.uv = vec2<f32>((p.x - draw.extent.x) / draw.extent.z, (draw.extent.y - p.y) / draw.extent.w);
    o.puv = m.yz;
    return o;
}

@vertex
fn vs_uv_morph(@location(0) p: vec3<f32>, @location(1) uv: vec2<f32>, @location(2) m: vec3<f32>) -> VOut {
    var o: VOut;
    let q = vec3<f32>(p.xy, mix(p.z, m.x, draw.morph.x));
    o.pos = draw.mvp * vec4<f32>(q, 1.0);
    o.uv = uv;
    o.puv = m.yz;
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

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    var c: vec4<f32>;
    var n_raw: vec3<f32>;
    let t = draw.morph.x;
    if t > 0.0 && draw.morph.w > 0.5 {
        // Blend towards the parent's textures at the same surface point.
        let cc = textureSample(colour_tex, samp, i.uv);
        let cp = textureSample(parent_colour, samp, i.puv);
        c = mix(cc, cp, t);
        let nc = textureSample(normal_tex, samp, i.uv).xyz;
        let np = textureSample(parent_normal, samp, i.puv).xyz;
        n_raw = mix(nc, np, t) * 2.0 - vec3<f32>(1.0);
    } else if t > 0.0 {
        // Parent not resident: the cell's own textures at up to the parent's texel density.
        let gx = dpdx(i.uv);
        let gy = dpdy(i.uv);
        let sc = morph_grad_scale(gx, gy, vec2<f32>(textureDimensions(colour_tex, 0)), draw.morph.y, t);
        let sn = morph_grad_scale(gx, gy, vec2<f32>(textureDimensions(normal_tex, 0)), draw.morph.z, t);
        c = textureSampleGrad(colour_tex, samp, i.uv, gx * sc, gy * sc);
        n_raw = textureSampleGrad(normal_tex, samp, i.uv, gx * sn, gy * sn).xyz * 2.0 - vec3<f32>(1.0);
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
