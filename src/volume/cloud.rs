//! Seed 002's procedural cloud on the CPU: the function the built-in density march evaluates on
//! the GPU, sampled at voxel centres for the texture march.

use glam::Vec3;

/// The procedural cloud at texture coordinate `u` of the unit box: fBm of value noise (5
/// octaves, lacunarity 2.03, gain ½) shaped by a soft ellipsoid, in [0, 1]. The function
/// [`fbm_cloud`] samples at voxel centres and `shaders/shared/fbm_cloud.wesl` evaluates on the
/// GPU ([`CloudMarch`](super::CloudMarch), seed 0).
pub fn fbm_cloud_at(u: Vec3, seed: u32) -> f32 {
    let hash = |x: i32, y: i32, z: i32, o: u32| -> f32 {
        let mut h = (x as u32).wrapping_mul(0x8da6_b343)
            ^ (y as u32).wrapping_mul(0xd816_3841)
            ^ (z as u32).wrapping_mul(0xcb1a_b31f)
            ^ seed.wrapping_mul(0x1656_67b1)
            ^ o.wrapping_mul(0x27d4_eb2d);
        h ^= h >> 15;
        h = h.wrapping_mul(0x2c1b_3c6d);
        h ^= h >> 12;
        (h & 0xffff) as f32 / 65535.0
    };
    let noise = |p: Vec3, o: u32| -> f32 {
        let i = p.floor();
        let f = p - i;
        let s = f * f * (Vec3::splat(3.0) - 2.0 * f);
        let (x, y, z) = (i.x as i32, i.y as i32, i.z as i32);
        let c = |dx, dy, dz| hash(x + dx, y + dy, z + dz, o);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let x00 = lerp(c(0, 0, 0), c(1, 0, 0), s.x);
        let x10 = lerp(c(0, 1, 0), c(1, 1, 0), s.x);
        let x01 = lerp(c(0, 0, 1), c(1, 0, 1), s.x);
        let x11 = lerp(c(0, 1, 1), c(1, 1, 1), s.x);
        lerp(lerp(x00, x10, s.y), lerp(x01, x11, s.y), s.z)
    };
    let q = (u - 0.5) * Vec3::new(2.0, 2.6, 2.0);
    let shape = (1.0 - q.length_squared()).max(0.0);
    let mut sum = 0.0;
    let mut amp = 0.5;
    let mut p = u * 4.0;
    for o in 0..5 {
        sum += amp * noise(p, o);
        p *= 2.03;
        amp *= 0.5;
    }
    ((sum - 0.35) * 2.2 * shape.sqrt()).clamp(0.0, 1.0)
}

/// The procedural cloud ([`fbm_cloud_at`]) at the voxel centres of a `dims` grid over the unit
/// box, x fastest. Deterministic for a `seed`.
pub fn fbm_cloud(dims: [u32; 3], seed: u32) -> Vec<f32> {
    let slice = (dims[0] * dims[1]) as usize;
    let mut out = vec![0.0f32; slice * dims[2] as usize];
    let voxel = |x: u32, y: u32, z: u32| {
        let u = (Vec3::new(x as f32, y as f32, z as f32) + 0.5)
            / Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
        fbm_cloud_at(u, seed)
    };
    // Slabs of z on every core: 512³ is 134 M voxels.
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per = (dims[2] as usize).div_ceil(threads).max(1) * slice;
    std::thread::scope(|scope| {
        for (k, chunk) in out.chunks_mut(per).enumerate() {
            let voxel = &voxel;
            scope.spawn(move || {
                for (i, v) in chunk.iter_mut().enumerate() {
                    let at = k * per + i;
                    let (z, r) = (at / slice, at % slice);
                    *v = voxel(
                        (r % dims[0] as usize) as u32,
                        (r / dims[0] as usize) as u32,
                        z as u32,
                    );
                }
            });
        }
    });
    out
}
