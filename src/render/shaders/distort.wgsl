// cliffmap distortion pass: resamples the pinhole image of a frame through the camera's radial
// distortion (ImGRAFT camera.m model, see src/camera/mod.rs). One full-screen triangle; each
// output pixel undistorts its normalized coordinates by Newton's method and samples the pinhole
// image bilinearly there. Mirrors render::distortion::undistort_radius_f32.

struct Params {
    // Output (distorted) camera: fx, fy, cx, cy (pixels, 0-based pixel-centre convention).
    out_f: vec4<f32>,
    // k1, k2, Newton steps, the largest normalized distorted radius with a ray (the model's
    // fold; pixels beyond it have no ray and show the sky).
    k: vec4<f32>,
    // Pinhole view: fx, fy, cx, cy.
    src_f: vec4<f32>,
    // Pinhole view size (width, height) in pixels, unused, unused.
    src_size: vec4<f32>,
    // Linear sky colour for output pixels with no pinhole sample.
    sky: vec4<f32>,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d<f32>;
@group(0) @binding(2) var samp: sampler;

@vertex
fn vs_full(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (-1, 1), (3, 1), (-1, -3): one triangle over the whole target.
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
}

fn undistort_radius(rd: f32) -> f32 {
    let k1 = params.k.x;
    let k2 = params.k.y;
    let steps = i32(params.k.z);
    var r = rd;
    for (var n = 0; n < steps; n = n + 1) {
        let s = min(r * r, 4.0);
        let d = 1.0 + k1 * s + k2 * s * s;
        var df = d;
        if r * r < 4.0 {
            df = 1.0 + 3.0 * k1 * s + 5.0 * k2 * s * s;
        }
        if df <= 0.0 {
            break;
        }
        r = max(r - (r * d - rd) / df, 0.0);
    }
    return r;
}

@fragment
fn fs_distort(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    // Fragment coordinates are pixel centres at +0.5; the camera model puts them at integers.
    let u = frag.x - 0.5;
    let v = frag.y - 0.5;
    let xd = (u - params.out_f.z) / params.out_f.x;
    let yd = (v - params.out_f.w) / params.out_f.y;
    let rd = sqrt(xd * xd + yd * yd);
    if rd > params.k.w {
        return params.sky;
    }
    var s = 1.0;
    if rd > 0.0 {
        s = undistort_radius(rd) / rd;
    }
    let su = params.src_f.x * xd * s + params.src_f.z;
    let sv = params.src_f.y * yd * s + params.src_f.w;
    let uv = vec2<f32>((su + 0.5) / params.src_size.x, (sv + 0.5) / params.src_size.y);
    let c = textureSampleLevel(src, samp, uv, 0.0);
    if uv.x < 0.0 || uv.y < 0.0 || uv.x > 1.0 || uv.y > 1.0 {
        return params.sky;
    }
    return c;
}
