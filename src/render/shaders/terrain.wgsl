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
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> draw: Draw;
@group(1) @binding(0) var colour_tex: texture_2d<f32>;
@group(1) @binding(1) var normal_tex: texture_2d<f32>;
@group(1) @binding(2) var samp: sampler;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

// Orthographic cells: u east, v south over the nominal square.
@vertex
fn vs_ortho(@location(0) p: vec3<f32>) -> VOut {
    var o: VOut;
    o.pos = draw.mvp * vec4<f32>(p, 1.0);
    o.uv = vec2<f32>((p.x - draw.extent.x) / draw.extent.z, (draw.extent.y - p.y) / draw.extent.w);
    return o;
}

// Cells with stored texture coordinates (reparameterized charts).
@vertex
fn vs_uv(@location(0) p: vec3<f32>, @location(1) uv: vec2<f32>) -> VOut {
    var o: VOut;
    o.pos = draw.mvp * vec4<f32>(p, 1.0);
    o.uv = uv;
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let c = textureSample(colour_tex, samp, i.uv);
    let n_raw = textureSample(normal_tex, samp, i.uv).xyz * 2.0 - vec3<f32>(1.0);
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
