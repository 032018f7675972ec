// The scene's objects: triangles drawn with depth behind the billboard, so that the glow blends over them as over
// the background, and lit at every pixel by every source (objects::lighting): the fragment evaluates each source's
// term of psi at the pixel's surface point and the direction to the point of the source that term reads, with the
// field's own functions (imported with the field pass's bindings 0 to 6 and 9 to 11, which it shares), and shades
// `albedo (AMBIENT + S sum_i Ce_i psi_i max(0, n . l_i))`, the light of negative sources (which darken) apart, with
// a factor of its own. The shadow factor S (the share of the direct light the
// objects' shadows leave) is worked out in f64 at the vertices and interpolated. Rust side: src/gpu/object_pass.rs
// (gpu_data::ObjectParams, ObjectVertex; keep in sync). CPU twin: src/reference/objects.rs.
#import shared/brightest.wgsl

struct ObjectParams {
    view_proj: mat4x4<f32>,
    energy: vec3<f32>, // the scene's Ce, its intensity applied: each term's color is energy + its tint
    ambient: f32,      // objects::lighting::AMBIENT
    eye: vec3<f32>,    // the camera: a translucent surface's exit angle
    pad0: f32,
}

@group(0) @binding(14) var<uniform> object: ObjectParams;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) shadow: vec3<f32>,
    @location(4) shadow_dark: vec3<f32>,
    @location(5) subsurface: vec3<f32>,
    @location(6) eta: f32,
}

@vertex
fn vs_main(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
    @location(3) shadow: vec3<f32>,
    @location(4) shadow_dark: vec3<f32>,
    @location(5) subsurface: vec3<f32>,
    @location(6) eta: f32,
) -> VertexOut {
    var out: VertexOut;
    out.position = object.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    out.albedo = albedo;
    out.shadow = shadow;
    out.shadow_dark = shadow_dark;
    out.subsurface = subsurface;
    out.eta = eta;
    return out;
}

struct FragmentOut {
    // The lit color, unclamped (an HDR export keeps it; the display clamps), opaque.
    @location(0) color: vec4<f32>,
    // The bits of the fragment's depth, a copy of what the depth test keeps, for the billboard to read (a depth
    // texture cannot be read on GL, nor rg32float rendered there: gpu::formats::DEPTH_VALUE_FORMAT); twice: the
    // pipeline of the translucent triangles, drawn after the opaque ones, writes the first alone, so that the
    // second keeps the nearest opaque surface.
    @location(1) depth: vec2<u32>,
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    load_scalars();
    let l = length(in.normal);
    let n = select(vec3<f32>(0.0), in.normal / l, l > 0.0);
    // The depth's bits, the lowest one a flag: set on a translucent surface (the glow is seen through it: the
    // billboard does not let it hide the glow, only guide the glow's edge), clear on an opaque one. One unit in
    // the last place of the depth, which nothing reads that finely.
    let bits = bitcast<u32>(in.position.z);
    let depth = select(bits & ~1u, bits | 1u, in.eta > 0.0);
    if in.eta > 0.0 {
        // A translucent surface: the light its voxels scatter out, through the exit's Fresnel toward the eye
        // (objects::lighting::shaded_translucent).
        let to_eye = object.eye - in.world;
        let d_eye = length(to_eye);
        let cos_view = select(1.0, abs(dot(n, to_eye / d_eye)), d_eye > 0.0 && l > 0.0);
        let t = fresnel_transmittance(in.eta, cos_view);
        return FragmentOut(vec4<f32>(in.albedo * t * (object.ambient + in.subsurface), 1.0), vec2<u32>(depth));
    }
    let d = direct_light(in.world, n);
    let e = object.ambient + in.shadow * d.bright + in.shadow_dark * d.dark;
    return FragmentOut(vec4<f32>(in.albedo * e, 1.0), vec2<u32>(depth));
}

// The unpolarised Fresnel transmittance of light crossing at cos_outside into or out of a medium of relative
// index eta: 1 - (rs^2 + rp^2) / 2, 0 past the critical angle. Twin of objects::translucent::fresnel_transmittance.
fn fresnel_transmittance(eta: f32, cos_outside: f32) -> f32 {
    let c = min(abs(cos_outside), 1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 0.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let rs = (c - eta * cos_t) / (c + eta * cos_t);
    let rp = (eta * c - cos_t) / (eta * c + cos_t);
    return clamp(1.0 - 0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

// Lambert's cosine at x (normal n) of the light from `source`; 1 at the source itself, where the light comes from
// every side. Twin of lighting::cosine.
fn cosine_from(x: vec3<f32>, n: vec3<f32>, source: vec3<f32>) -> f32 {
    let to = source - x;
    let d = length(to);
    if d > 0.0 {
        return max(0.0, dot(n, to / d));
    }
    return 1.0;
}

// The direct light of the sources of positive coefficient, and of those of negative (which darken), each with a
// shadow factor of its own.
struct Direct {
    bright: vec3<f32>,
    dark: vec3<f32>,
}

// A term's light added to the part of its sign.
fn add_light(e: Direct, light: vec3<f32>, lambert: f32) -> Direct {
    if lambert < 0.0 {
        return Direct(e.bright, e.dark + light * lambert);
    }
    return Direct(e.bright + light * lambert, e.dark);
}

// Every source's light at x on a surface of normal n, unshadowed: sum_i Ce_i psi_i max(0, n . l_i), l_i toward
// the point of source i its term reads (twin of Lights::direct and Lights::at).
fn direct_light(x: vec3<f32>, n: vec3<f32>) -> Direct {
    var e = Direct(vec3<f32>(0.0), vec3<f32>(0.0));
    var t = 0u;
    for (var k = 0u; k < point_count(); k++) {
        let p = points[k];
        let strength = p.coefficient * falloff(length(x - p.position), EPSILON);
        e = add_light(e, object.energy + tints[t].xyz, strength * cosine_from(x, n, p.position));
        t++;
    }
    for (var k = 0u; k < line_count(); k++) {
        let l = lines[k];
        let foot = l.point + l.direction * dot(x - l.point, l.direction);
        let strength = l.coefficient * falloff(line_distance(x, l.point, l.direction), EPSILON);
        e = add_light(e, object.energy + tints[t].xyz, strength * cosine_from(x, n, foot));
        t++;
    }
    for (var k = 0u; k < torus_count(); k++) {
        let r = tori[k];
        let strength = r.coefficient * falloff(torus_distance(x, r.center, r.axis, r.major_radius), EPSILON);
        e = add_light(e, object.energy + tints[t].xyz, strength * cosine_from(x, n, ring_point(r, x)));
        t++;
    }
    for (var k = 0u; k < curve_count(); k++) {
        let c = curves[k];
        if c.segment_count > 0u {
            // (t, distance) of the point the term reads; a curve with a color series has the tint -Ce.
            let held = held_chain(c);
            let seen = curve_point(c, held, x);
            let strength = c.coefficient * wseries(c, held.weights, seen.x) * falloff(seen.y, EPSILON);
            let color = object.energy + tints[t].xyz + color_series(c, seen.x);
            e = add_light(e, color, strength * cosine_from(x, n, chain_point(c, seen.x)));
        }
        t++;
    }
    return e;
}

// The point of a ring nearest x: on the axis, where every point is, the one glam's any_orthonormal_vector picks
// (as the twin does).
fn ring_point(r: TorusSource, x: vec3<f32>) -> vec3<f32> {
    let q = x - r.center;
    let across = q - r.axis * dot(q, r.axis);
    let l = length(across);
    if l > 0.0 {
        return r.center + across / l * r.major_radius;
    }
    let a = r.axis;
    let s = select(-1.0, 1.0, a.z >= 0.0);
    let m = -1.0 / (s + a.z);
    let any = vec3<f32>(a.x * a.y * m, s + a.y * a.y * m, -a.y);
    return r.center + any * r.major_radius;
}

// The point of a chain at chain parameter t in [0, 1] (segment j covers [j, j + 1] / k). Twin of
// curve::chain_frame.
fn chain_point(c: CurveSource, t: f32) -> vec3<f32> {
    let x = clamp(t, 0.0, 1.0) * f32(c.segment_count);
    let j = min(u32(floor(x)), c.segment_count - 1u);
    return segment_at(segments[c.first_segment + j], x - f32(j));
}
