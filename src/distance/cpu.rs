//! CPU reference for the distance stages, to read beside the shaders: an exact Euclidean distance
//! transform (Felzenszwalb & Huttenlocher 2012, "Distance Transforms of Sampled Functions"), and a
//! plain-Rust JFA that follows the shader pass for pass.

/// Squared distance value for "no seed anywhere".
pub const NONE: u64 = u64::MAX;

/// 1D squared distance transform of `f` (lower envelope of parabolas rooted at finite samples).
/// Values are integers below 2^53, so f64 arithmetic is exact.
fn edt_1d(f: &[f64], out: &mut [f64]) {
    let n = f.len();
    // Only finite samples root a parabola; with none, every output stays infinite.
    let roots: Vec<usize> = (0..n).filter(|&i| f[i].is_finite()).collect();
    if roots.is_empty() {
        out.iter_mut().for_each(|o| *o = f64::INFINITY);
        return;
    }
    let mut v = Vec::with_capacity(roots.len());
    let mut z: Vec<f64> = Vec::with_capacity(roots.len() + 1);
    v.push(roots[0]);
    z.push(f64::NEG_INFINITY);
    z.push(f64::INFINITY);
    for &q in &roots[1..] {
        loop {
            let p = *v.last().unwrap();
            let s =
                ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            if s <= z[v.len() - 1] {
                v.pop();
                z.pop();
                if v.is_empty() {
                    v.push(q);
                    z.push(f64::INFINITY);
                    z[0] = f64::NEG_INFINITY;
                    break;
                }
            } else {
                *z.last_mut().unwrap() = s;
                v.push(q);
                z.push(f64::INFINITY);
                break;
            }
        }
    }
    let mut k = 0;
    for (qi, o) in out.iter_mut().enumerate() {
        let q = qi as f64;
        while z[k + 1] < q {
            k += 1;
        }
        let d = q - v[k] as f64;
        *o = d * d + f[v[k]];
    }
}

/// Exact squared Euclidean distance from every texel centre to the nearest seed texel centre
/// (`seeds[y * width + x]`), or [`NONE`] when there is no seed.
pub fn edt_2d_squared(seeds: &[bool], width: usize, height: usize) -> Vec<u64> {
    assert_eq!(seeds.len(), width * height, "seed mask size");
    let mut g = vec![0f64; width * height];
    // Columns first, then rows.
    let mut col = vec![0f64; height];
    let mut col_out = vec![0f64; height];
    for x in 0..width {
        for y in 0..height {
            col[y] = if seeds[y * width + x] {
                0.0
            } else {
                f64::INFINITY
            };
        }
        edt_1d(&col, &mut col_out);
        for y in 0..height {
            g[y * width + x] = col_out[y];
        }
    }
    let mut out = vec![NONE; width * height];
    let mut row_out = vec![0f64; width];
    for y in 0..height {
        edt_1d(&g[y * width..(y + 1) * width], &mut row_out);
        for x in 0..width {
            if row_out[x].is_finite() {
                out[y * width + x] = row_out[x] as u64;
            }
        }
    }
    out
}

/// Combine the two transforms as the resolve stages do (shared by 2D and 3D).
fn signed_from(mask: &[bool], to_inside: &[u64], to_outside: &[u64]) -> Vec<f64> {
    let half_off = |d2: u64, far: f64| {
        if d2 == NONE {
            far
        } else {
            (d2 as f64).sqrt() - 0.5
        }
    };
    (0..mask.len())
        .map(|i| {
            if mask[i] {
                -half_off(to_outside[i], f32::MAX as f64)
            } else {
                half_off(to_inside[i], f32::MAX as f64)
            }
        })
        .collect()
}

/// Signed distance as the GPU resolves it: outside, distance to the nearest inside centre minus
/// half a texel; inside, minus (distance to the nearest outside centre minus half a texel).
/// `±f32::MAX` where the other side does not exist.
pub fn signed_2d(mask: &[bool], width: usize, height: usize) -> Vec<f64> {
    let to_inside = edt_2d_squared(mask, width, height);
    let outside: Vec<bool> = mask.iter().map(|m| !m).collect();
    let to_outside = edt_2d_squared(&outside, width, height);
    signed_from(mask, &to_inside, &to_outside)
}

/// The JFA the shaders run, on the CPU: same step order, same 8-neighbour test, same skipping of
/// out-of-range texels and the same tie-break (smaller packed seed). Returns packed seeds.
pub fn jfa_2d(seeds: &[bool], width: usize, height: usize, steps: &[u32]) -> Vec<u32> {
    let pack = |x: usize, y: usize| ((x + 1) | ((y + 1) << 16)) as u32;
    let d2 = |s: u32, x: i64, y: i64| -> u64 {
        let (sx, sy) = ((s & 0xffff) as i64 - 1, (s >> 16) as i64 - 1);
        ((sx - x) * (sx - x) + (sy - y) * (sy - y)) as u64
    };
    let mut cur: Vec<u32> = (0..width * height)
        .map(|i| {
            if seeds[i] {
                pack(i % width, i / width)
            } else {
                0
            }
        })
        .collect();
    let mut next = cur.clone();
    for &step in steps {
        let step = step as i64;
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let mut best = cur[(y * width as i64 + x) as usize];
                let mut best_d = if best == 0 { u64::MAX } else { d2(best, x, y) };
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (qx, qy) = (x + dx * step, y + dy * step);
                        if (dx == 0 && dy == 0)
                            || qx < 0
                            || qy < 0
                            || qx >= width as i64
                            || qy >= height as i64
                        {
                            continue;
                        }
                        let s = cur[(qy * width as i64 + qx) as usize];
                        if s == 0 {
                            continue;
                        }
                        let d = d2(s, x, y);
                        if d < best_d || (d == best_d && s < best) {
                            best = s;
                            best_d = d;
                        }
                    }
                }
                next[(y * width as i64 + x) as usize] = best;
            }
        }
        std::mem::swap(&mut cur, &mut next);
    }
    cur
}

/// Exact squared Euclidean distance from every voxel centre to the nearest seed voxel centre
/// (`seeds[(z * height + y) * width + x]`), or [`NONE`]: the same 1D transform along x, y, z.
pub fn edt_3d_squared(seeds: &[bool], size: [usize; 3]) -> Vec<u64> {
    let [w, h, d] = size;
    assert_eq!(seeds.len(), w * h * d, "seed mask size");
    let mut g: Vec<f64> = seeds
        .iter()
        .map(|&s| if s { 0.0 } else { f64::INFINITY })
        .collect();
    let mut line = Vec::new();
    let mut out = Vec::new();
    // One axis at a time: gather each line, transform it, scatter it back.
    for (axis, (n, stride, lines)) in [(w, 1, h * d), (h, w, w * d), (d, w * h, w * h)]
        .into_iter()
        .enumerate()
    {
        line.resize(n, 0.0);
        out.resize(n, 0.0);
        for l in 0..lines {
            // Lines are numbered over the other two axes, x first.
            let base = match axis {
                0 => l * w,
                1 => (l / w) * w * h + l % w,
                _ => l,
            };
            for i in 0..n {
                line[i] = g[base + i * stride];
            }
            edt_1d(&line, &mut out);
            for i in 0..n {
                g[base + i * stride] = out[i];
            }
        }
    }
    g.into_iter()
        .map(|v| if v.is_finite() { v as u64 } else { NONE })
        .collect()
}

/// Signed 3D distance as the GPU resolves it (see [`signed_2d`]).
pub fn signed_3d(mask: &[bool], size: [usize; 3]) -> Vec<f64> {
    let to_inside = edt_3d_squared(mask, size);
    let outside: Vec<bool> = mask.iter().map(|m| !m).collect();
    let to_outside = edt_3d_squared(&outside, size);
    signed_from(mask, &to_inside, &to_outside)
}

/// Pack a 3D seed as the shaders do (11/11/10 bits, the whole code + 1).
pub fn pack_seed3(x: usize, y: usize, z: usize) -> u32 {
    ((x | (y << 11) | (z << 22)) + 1) as u32
}

/// Unpack a 3D seed; `None` for no seed.
pub fn unpack_seed3(s: u32) -> Option<[i64; 3]> {
    (s != 0).then(|| {
        let c = s - 1;
        [
            (c & 0x7ff) as i64,
            ((c >> 11) & 0x7ff) as i64,
            (c >> 22) as i64,
        ]
    })
}

/// Squared distance from voxel `i` of a `size` grid to packed seed `s`.
pub fn seed_d2_3(s: u32, i: usize, size: [usize; 3]) -> Option<u64> {
    let [sx, sy, sz] = unpack_seed3(s)?;
    let (x, y, z) = (
        (i % size[0]) as i64,
        ((i / size[0]) % size[1]) as i64,
        (i / (size[0] * size[1])) as i64,
    );
    Some(((sx - x).pow(2) + (sy - y).pow(2) + (sz - z).pow(2)) as u64)
}

/// The 3D JFA the shaders run (`jfa3_step.wgsl`, entry `jump`), on the CPU: 26 neighbours,
/// out-of-range skipped, ties to the smaller packed seed. Returns packed seeds.
pub fn jfa_3d(seeds: &[bool], size: [usize; 3], steps: &[u32]) -> Vec<u32> {
    let [w, h, d] = size;
    let mut cur: Vec<u32> = (0..w * h * d)
        .map(|i| {
            if seeds[i] {
                pack_seed3(i % w, (i / w) % h, i / (w * h))
            } else {
                0
            }
        })
        .collect();
    let mut next = cur.clone();
    for &step in steps {
        let step = step as i64;
        for i in 0..cur.len() {
            let p = [(i % w) as i64, ((i / w) % h) as i64, (i / (w * h)) as i64];
            let mut best = cur[i];
            let mut best_d = seed_d2_3(best, i, size).unwrap_or(u64::MAX);
            for dz in -1..=1i64 {
                for dy in -1..=1i64 {
                    for dx in -1..=1i64 {
                        let q = [p[0] + dx * step, p[1] + dy * step, p[2] + dz * step];
                        if (dx, dy, dz) == (0, 0, 0)
                            || q.iter().zip(size).any(|(&c, n)| c < 0 || c >= n as i64)
                        {
                            continue;
                        }
                        let s = cur[((q[2] * h as i64 + q[1]) * w as i64 + q[0]) as usize];
                        let Some(dd) = seed_d2_3(s, i, size) else {
                            continue;
                        };
                        if dd < best_d || (dd == best_d && s < best) {
                            best = s;
                            best_d = dd;
                        }
                    }
                }
            }
            next[i] = best;
        }
        std::mem::swap(&mut cur, &mut next);
    }
    cur
}

/// Brute force in 3D, for checking the reference itself.
pub fn brute_3d_squared(seeds: &[bool], size: [usize; 3]) -> Vec<u64> {
    let [w, h, _] = size;
    let coord = |i: usize| [(i % w) as i64, ((i / w) % h) as i64, (i / (w * h)) as i64];
    let pts: Vec<[i64; 3]> = (0..seeds.len()).filter(|&i| seeds[i]).map(coord).collect();
    (0..seeds.len())
        .map(|i| {
            let p = coord(i);
            pts.iter()
                .map(|s| {
                    ((s[0] - p[0]).pow(2) + (s[1] - p[1]).pow(2) + (s[2] - p[2]).pow(2)) as u64
                })
                .min()
                .unwrap_or(NONE)
        })
        .collect()
}

/// Brute force, for checking the reference itself on small grids.
pub fn brute_2d_squared(seeds: &[bool], width: usize, height: usize) -> Vec<u64> {
    let pts: Vec<(i64, i64)> = (0..seeds.len())
        .filter(|&i| seeds[i])
        .map(|i| ((i % width) as i64, (i / width) as i64))
        .collect();
    (0..width * height)
        .map(|i| {
            let (x, y) = ((i % width) as i64, (i / width) as i64);
            pts.iter()
                .map(|&(sx, sy)| ((sx - x).pow(2) + (sy - y).pow(2)) as u64)
                .min()
                .unwrap_or(NONE)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small deterministic generator so the test needs no crate.
    fn lcg_mask(n: usize, density: f64, seed: u64) -> Vec<bool> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) < density
            })
            .collect()
    }

    #[test]
    fn edt_matches_brute_force() {
        for (w, h, density, seed) in [
            (17, 9, 0.05, 1),
            (31, 40, 0.01, 2),
            (8, 8, 0.5, 3),
            (1, 13, 0.2, 4),
            (23, 1, 0.1, 5),
        ] {
            let m = lcg_mask(w * h, density, seed);
            assert_eq!(
                edt_2d_squared(&m, w, h),
                brute_2d_squared(&m, w, h),
                "{w}x{h} density {density}"
            );
        }
    }

    #[test]
    fn edt_3d_matches_brute_force() {
        for (size, density, seed) in [
            ([9, 7, 5], 0.03, 1),
            ([16, 3, 11], 0.01, 2),
            ([6, 6, 6], 0.4, 3),
            ([1, 1, 9], 0.2, 4),
            ([1, 8, 6], 0.1, 6),
            ([12, 10, 1], 0.05, 5),
        ] {
            let m = lcg_mask(size.iter().product(), density, seed);
            assert_eq!(
                edt_3d_squared(&m, size),
                brute_3d_squared(&m, size),
                "{size:?} density {density}"
            );
        }
    }

    #[test]
    fn no_seeds_is_none_everywhere() {
        assert!(
            edt_2d_squared(&[false; 12], 4, 3)
                .iter()
                .all(|&d| d == NONE)
        );
    }

    #[test]
    fn jfa_plus_2_matches_exact_on_random_seeds() {
        let (w, h) = (37, 29);
        let m = lcg_mask(w * h, 0.02, 7);
        let exact = edt_2d_squared(&m, w, h);
        let steps = crate::distance::Variant::JfaPlus2.steps(w.max(h) as u32);
        let got = jfa_2d(&m, w, h, &steps);
        for (i, (&s, &e)) in got.iter().zip(&exact).enumerate() {
            let (sx, sy) = ((s & 0xffff) as i64 - 1, (s >> 16) as i64 - 1);
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            assert_eq!(((sx - x).pow(2) + (sy - y).pow(2)) as u64, e);
        }
    }
}
