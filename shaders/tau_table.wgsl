// The optical-thickness table of a translucent object on the GPU: tau(k, l) between surface voxels k and l, the
// integral of the extinction along the straight segment between their points through the voxels (Amanatides and
// Woo's traversal: each voxel crossed adds its extinction times the length inside it). One invocation a pair,
// a band of rows k0 .. k0 + rows a dispatch, written as the table keeps them: row k holds l = k .. n - 1 after
// the rows before it. Rust side: src/gpu/tau_table.rs. CPU twin: objects::translucent::table.

struct TauParams {
    origin: vec3<f32>,  // the grid's lowest corner
    side: f32,          // a voxel's side
    dims: vec3<u32>,    // voxels along x, y and z
    n: u32,             // surface voxels
    k0: u32,            // the band's first row
    rows: u32,          // rows in the band
    base: u32,          // where row k0 starts in the table
    pad0: u32,
}

@group(0) @binding(0) var<storage, read> tau_params: TauParams;
// sigma_t at every voxel, x fastest, then y, then z.
@group(0) @binding(1) var<storage, read> extinction: array<f32>;
// Each surface voxel's point (w unused).
@group(0) @binding(2) var<storage, read> points: array<vec4<f32>>;
// The band's entries, from row k0's start.
@group(0) @binding(3) var<storage, read_write> band: array<f32>;

// The optical thickness of start -> end through the voxels.
fn thickness(start: vec3<f32>, end: vec3<f32>) -> f32 {
    let d = end - start;
    let length = sqrt(dot(d, d));
    if length == 0.0 {
        return 0.0;
    }
    let side = tau_params.side;
    let dims = vec3<i32>(tau_params.dims);
    let a = (start - tau_params.origin) / side;
    let dir = d / side;
    var cell = vec3<i32>(floor(a));
    var step = vec3<i32>(0);
    var next = vec3<f32>(3.0e38);
    var delta = vec3<f32>(3.0e38);
    for (var i = 0; i < 3; i++) {
        if dir[i] > 0.0 {
            step[i] = 1;
            next[i] = (f32(cell[i] + 1) - a[i]) / dir[i];
            delta[i] = 1.0 / dir[i];
        } else if dir[i] < 0.0 {
            step[i] = -1;
            next[i] = (f32(cell[i]) - a[i]) / dir[i];
            delta[i] = -1.0 / dir[i];
        }
    }
    var t = 0.0;
    var tau = 0.0;
    // At most one step a voxel boundary crossed: the grid's three sides, and a few more for rounding.
    let most = dims.x + dims.y + dims.z + 4;
    for (var s = 0; s < most; s++) {
        let t_next = min(min(min(next.x, next.y), next.z), 1.0);
        if all(cell >= vec3<i32>(0)) && all(cell < dims) {
            let v = u32(cell.x) + tau_params.dims.x * (u32(cell.y) + tau_params.dims.y * u32(cell.z));
            tau += extinction[v] * (t_next - t);
        }
        if t_next >= 1.0 {
            break;
        }
        t = t_next;
        if next.x <= next.y && next.x <= next.z {
            cell.x += step.x;
            next.x += delta.x;
        } else if next.y <= next.z {
            cell.y += step.y;
            next.y += delta.y;
        } else {
            cell.z += step.z;
            next.z += delta.z;
        }
    }
    return tau * length;
}

@compute @workgroup_size(64, 1, 1)
fn tau_table(@builtin(global_invocation_id) gid: vec3<u32>) {
    let l = gid.x;
    let row = gid.y + gid.z * 65535u;
    let n = tau_params.n;
    if row >= tau_params.rows || l >= n {
        return;
    }
    let k = tau_params.k0 + row;
    if l < k {
        return;
    }
    // Row k starts at k n - k (k - 1) / 2; the band at row k0's start.
    let start = k * n - (k * (k - 1u)) / 2u - tau_params.base;
    var value = 0.0;
    if l != k {
        value = thickness(points[k].xyz, points[l].xyz);
    }
    band[start + (l - k)] = value;
}
