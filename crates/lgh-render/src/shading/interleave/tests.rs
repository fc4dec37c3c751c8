//! Tests of the parent module.
use super::*;

#[test]
fn merge_inverts_split_exactly() {
    for (w, h, n) in [(7u32, 5u32, 2u32), (16, 9, 4), (3, 3, 8), (10, 10, 1)] {
        let data: Vec<u32> = (0..w * h).collect();
        let subs = split(&data, w, h, n);
        assert_eq!(subs.len(), (n * n) as usize);
        assert_eq!(subs.iter().map(Vec::len).sum::<usize>(), data.len());
        for (s, sub) in subs.iter().enumerate() {
            for &v in sub {
                assert_eq!(sub_image_of(v % w, v / w, n), s);
            }
        }
        assert_eq!(merge(&subs, w, h, n, u32::MAX), data);
    }
}

/// A G-buffer of two facing-camera planes side by side: columns < `split` at depth 1,
/// the rest at depth 3 (both with normal +z).
fn two_planes(w: u32, h: u32, split: u32) -> GBuffer {
    let n = (w * h) as usize;
    let mut depth = vec![0.0; n];
    let mut position = vec![Vec3::ZERO; n];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            depth[i] = if x < split { 1.0 } else { 3.0 };
            position[i] = Vec3::new(x as f32 * 0.01, y as f32 * 0.01, -depth[i]);
        }
    }
    GBuffer::from_planes((w, h), position, vec![Vec3::Z; n], depth)
}

#[test]
fn the_blur_never_mixes_pixels_across_a_depth_edge() {
    let (w, h, split) = (40u32, 12u32, 17u32);
    let g = two_planes(w, h, split);
    let p = BlurParams::defaults();
    let disc = discontinuities(&g, &p);
    // Values constant per plane, noisy within: the blur smooths each plane on its own.
    let img: Vec<Vec3> = (0..(w * h) as usize)
        .map(|i| {
            let x = i as u32 % w;
            let base = if x < split { 1.0 } else { 5.0 };
            Vec3::splat(base + if i % 3 == 0 { 0.3 } else { -0.15 })
        })
        .collect();
    let out = blur(&img, &g, &disc, &p);
    for (i, v) in out.iter().enumerate() {
        let x = i as u32 % w;
        let (lo, hi) = if x < split { (0.85, 1.3) } else { (4.85, 5.3) };
        assert!(v.x >= lo && v.x <= hi, "pixel {i} (x {x}): {v}");
    }
    // And it does smooth within a plane.
    let spread = |xs: &[Vec3]| {
        let (a, b) = xs
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v.x), b.max(v.x)));
        b - a
    };
    let row = (5 * w) as usize;
    assert!(spread(&out[row..row + 10]) < 0.5 * spread(&img[row..row + 10]));
}

/// Width, height, the column of the depth edge and n of the interleaving tests.
const EDGE: (u32, u32, u32, u32) = (40, 24, 17, 4);

/// The [`two_planes`] G-buffer of [`EDGE`], the default blur for n x n interleaving and
/// its discontinuities.
fn edge_blur() -> (GBuffer, BlurParams, Vec<u8>) {
    let (w, h, split, n) = EDGE;
    let g = two_planes(w, h, split);
    let p = BlurParams::defaults().with_phases(n);
    let disc = discontinuities(&g, &p);
    (g, p, disc)
}

/// A `w` x `h` image under n x n interleaving whose sub-image s holds the constant
/// 1 + 0.37 s, and the mean of the n^2 constants.
fn sub_image_constants(w: u32, h: u32, n: u32) -> (Vec<Vec3>, f32) {
    let value = |s: usize| 1.0 + s as f32 * 0.37;
    let img = (0..(w * h) as usize)
        .map(|i| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            Vec3::splat(value(sub_image_of(x, y, n)))
        })
        .collect();
    let subs = (n * n) as usize;
    (img, (0..subs).map(value).sum::<f32>() / subs as f32)
}

/// The recombination blur of the unshadowed sum (radius n / 2): on a 4 x 4 interleaved
/// image whose sub-images hold different constants, every pixel whose walk no edge or
/// border cuts holds exactly the mean of the 16 (to rounding, 1e-5), as a 17-tap blur
/// does; and a single bright pixel spreads over its 5 x 5 neighbourhood only, where the
/// wide blur spreads it over 17 x 17.
#[test]
fn the_recombination_counts_every_sub_image_once_within_n_pixels() {
    let (w, h, split, n) = EDGE;
    let (g, wide, disc) = edge_blur();
    let narrow = wide.recombination();
    assert_eq!(narrow.radius, 2);
    let (img, mean) = sub_image_constants(w, h, n);
    let out = blur(&img, &g, &disc, &narrow);
    for y in 2..h - 2 {
        for x in (2..split - 2).chain(split + 2..w - 2) {
            let v = out[(y * w + x) as usize].x;
            assert!((v - mean).abs() < 1e-5 * mean, "({x}, {y}): {v} vs {mean}");
        }
    }
    let mut spot = vec![Vec3::ZERO; (w * h) as usize];
    let (cx, cy) = (28u32, 12u32);
    spot[(cy * w + cx) as usize] = Vec3::ONE;
    let reach = |p: &BlurParams| {
        let out = blur(&spot, &g, &disc, p);
        (0..w)
            .filter(|&x| out[(cy * w + x) as usize].x > 0.0)
            .map(|x| x.abs_diff(cx))
            .max()
    };
    assert_eq!(reach(&narrow), Some(2));
    assert_eq!(reach(&wide), Some(8));
}

/// Two faces of one depth meeting at a vertical crease of 35 degrees (1 - n . n' = 0.18,
/// under the wide blur's `n_diff` 0.5, over `a_n_diff` 0.05), each face's unshadowed sum A
/// a constant under 2 x 2 interleaving: the recombination of A keeps every pixel at its
/// own face's value (the pixels along the crease too, whose walks are cut on one side),
/// where with `a_n_diff` at `n_diff` (before 2026-12-06) the two columns along the crease
/// took the other face's light. The wide blur of S and U still walks across the crease.
#[test]
fn the_recombination_of_a_stops_at_creases() {
    let (w, h, split, n) = (24u32, 10u32, 11u32, 2u32);
    let mut g = two_planes(w, h, split);
    let turned = Vec3::new(35f32.to_radians().sin(), 0.0, 35f32.to_radians().cos());
    for (i, (d, nrm)) in g.depth.iter_mut().zip(g.normal.iter_mut()).enumerate() {
        *d = 1.0;
        if (i as u32 % w) >= split {
            *nrm = turned;
        }
    }
    let face = |x: u32| if x < split { 1.0 } else { 3.0 };
    let img: Vec<Vec3> = (0..(w * h) as usize)
        .map(|i| Vec3::splat(face(i as u32 % w)))
        .collect();
    let p = BlurParams::defaults().with_phases(n);
    let out = blur(&img, &g, &discontinuities(&g, &p), &p.recombination());
    for (i, v) in out.iter().enumerate() {
        let x = i as u32 % w;
        assert!((v.x - face(x)).abs() < 1e-5, "pixel {i} (x {x}): {v}");
    }
    let old = BlurParams {
        a_n_diff: p.n_diff,
        ..p
    };
    let mixed = blur(&img, &g, &discontinuities(&g, &old), &old.recombination());
    let at = (3 * w + split) as usize;
    assert!(
        mixed[at].x < 2.9 && mixed[at - 1].x > 1.1,
        "{} {}",
        mixed[at - 1],
        mixed[at]
    );
    let wide = blur(&img, &g, &discontinuities(&g, &p), &p);
    assert!(wide[at].x < 2.9, "{}", wide[at]);
}

/// A 4 x 4 interleaved image whose sub-images hold different constants, on two planes
/// with a vertical depth edge: after the blur every pixel, those along the edge too,
/// holds the mean of all sub-images within 2% (no comb along the edge: the walk along
/// the edge is not stopped by the jump across it, and walks cut short are averaged phase
/// by phase).
#[test]
fn every_sub_image_counts_along_an_edge() {
    let (w, h, split, n) = EDGE;
    let (g, p, disc) = edge_blur();
    let (img, mean) = sub_image_constants(w, h, n);
    let out = blur(&img, &g, &disc, &p);
    for y in 0..h {
        for x in [split - 1, split, 2, w - 3] {
            let v = out[(y * w + x) as usize].x;
            assert!((v - mean).abs() < 0.02 * mean, "({x}, {y}): {v} vs {mean}");
        }
    }
}

#[test]
fn lattices_cover_every_pixel_once() {
    let (w, h) = (13u32, 7u32);
    for n in [1u32, 2, 4, 8] {
        let mut seen = vec![0u32; (w * h) as usize];
        for l in Lattice::all(n) {
            for y in 0..h {
                for x in 0..w {
                    if l.contains(x, y) {
                        seen[(y * w + x) as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "n = {n}");
    }
}

/// The blur with precomputed walks equals a plain walk that tests every tap (bounds,
/// a jump between the two pixels along the axis, pixel that sees nothing), bit for bit, on
/// random discontinuity maps with holes, for 1 and 3 images at once; the image is tall
/// enough for the vertical walks to be found in several blocks of rows.
#[test]
fn the_precomputed_walks_equal_a_plain_walk() {
    let (w, h) = (37u32, 3 * VERTICAL_BLOCK_ROWS as u32 + 7);
    let mut g = two_planes(w, h, 11);
    let n = (w * h) as usize;
    let mut rng = lgh_core::rng::Rng::new(&[5, 6]);
    for i in 0..n {
        if rng.next_f32() < 0.05 {
            g.depth[i] = f32::INFINITY;
        }
    }
    let disc: Vec<u8> = (0..n)
        .map(|_| u8::from(rng.next_f32() < 0.08) | (u8::from(rng.next_f32() < 0.08) << 1))
        .collect();
    let img = |seed: u64| -> Vec<Vec3> {
        let mut r = lgh_core::rng::Rng::new(&[seed]);
        (0..n)
            .map(|_| Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()))
            .collect()
    };
    let p = BlurParams::defaults();
    let weights: Vec<f32> = (0..=p.radius as usize)
        .map(|k| (-((k * k) as f32) / (2.0 * p.sigma * p.sigma)).exp())
        .collect();
    let plain = |src: &[Vec3], step: usize, len: usize, pos: &dyn Fn(usize) -> usize| {
        let bit = if step == 1 { JUMP_X } else { JUMP_Y };
        (0..n)
            .map(|i| {
                if !g.is_hit(i) {
                    return src[i];
                }
                let (mut sum, mut wsum) = (src[i] * weights[0], weights[0]);
                for dir in [1isize, -1] {
                    let mut j = i;
                    for (k, &wk) in weights.iter().enumerate().skip(1) {
                        let q = pos(i) as isize + dir * k as isize;
                        if q < 0 || q >= len as isize {
                            break;
                        }
                        let prev = j;
                        j = (j as isize + dir * step as isize) as usize;
                        if disc[prev.min(j)] & bit != 0 || !g.is_hit(j) {
                            break;
                        }
                        sum += src[j] * wk;
                        wsum += wk;
                    }
                }
                sum / wsum
            })
            .collect::<Vec<_>>()
    };
    let (wu, hu) = (w as usize, h as usize);
    let reference = |src: &[Vec3]| {
        let horizontal = plain(src, 1, wu, &|i| i % wu);
        plain(&horizontal, wu, hu, &|i| i / wu)
    };
    // Equal up to float rounding: runs of full walks are summed in another order. A
    // wrong set of taps would differ by about 1e-2 (values in [0, 1)).
    let close = |x: &[Vec3], y: &[Vec3]| {
        let worst = x
            .iter()
            .zip(y)
            .map(|(p, q)| (*p - *q).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(worst < 2e-6, "largest difference {worst}");
    };
    let (a, b, c) = (img(1), img(2), img(3));
    close(&blur(&a, &g, &disc, &p), &reference(&a));
    let [a2, b2, c2] = blur_n([a.clone(), b.clone(), c.clone()], &g, &disc, &p);
    close(&a2, &reference(&a));
    close(&b2, &reference(&b));
    close(&c2, &reference(&c));
}

/// The stop on A: on one plane (no geometric edge) whose keys step by 1 at column 20, an
/// image of 1 left of the step and 3 right of it keeps both values exactly where the walks
/// stop at the step (a_diff 0.05), while without keys the walks cross it and mix them
/// (the pixels beside the step move by more than 0.1); with keys but a_diff 0 the blur is
/// the plain one.
#[test]
fn walks_stop_where_the_key_of_a_moves() {
    let (w, h) = (40u32, 24u32);
    let g = two_planes(w, h, w);
    let p = BlurParams {
        phases: 1,
        ..BlurParams::defaults()
    };
    let disc = discontinuities(&g, &p);
    let left = |i: usize| (i % w as usize) < 20;
    let img: Vec<Vec3> = (0..g.len())
        .map(|i| Vec3::splat(if left(i) { 1.0 } else { 3.0 }))
        .collect();
    let keys: Vec<f32> = (0..g.len())
        .map(|i| if left(i) { 0.0 } else { 1.0 })
        .collect();
    let [stopped] = blur_n_stopped([img.clone()], &g, &disc, &p, Stop::Keys(&keys));
    for (i, v) in stopped.iter().enumerate() {
        assert!((v.x - img[i].x).abs() <= 1e-6, "pixel {i}: {v}");
    }
    let [plain] = blur_n([img.clone()], &g, &disc, &p);
    let beside = 10 * w as usize + 19;
    assert!(plain[beside].x - img[beside].x > 0.1, "{}", plain[beside]);
    let off = BlurParams { a_diff: 0.0, ..p };
    let [unkeyed] = blur_n_stopped([img.clone()], &g, &disc, &off, Stop::Keys(&keys));
    let [plain_off] = blur_n([img], &g, &disc, &off);
    assert_eq!(unkeyed, plain_off);
}

/// The stop on A under 4 x 4 interleaving, on one plane whose unshadowed sum A steps from
/// 1 to 3 at column 50, each pixel's A off by up to 20% (the noise of its sub-image's
/// lights, which the recombination does not remove): with [`Stop::SmoothedA`] (A smoothed
/// by the wide blur) the walks of S and U still stop at the step, so the pixels beside it
/// keep their side's ratio, and away from it and the borders fewer than 5% of the walks
/// stop; with the keys of A as recombined (`Stop::Keys`, the stop before the
/// twenty-seventh session) the noise stops more than half of them.
#[test]
fn the_stop_on_a_passes_over_the_noise_of_the_sub_images() {
    let (w, h, n, step) = (100u32, 40u32, 4u32, 50u32);
    let g = two_planes(w, h, w);
    let p = BlurParams::defaults().with_phases(n);
    let disc = discontinuities(&g, &p);
    // Uniform in 0.8..1.2, a hash of the pixel.
    let noise = |i: usize| {
        let v = (i as u32).wrapping_mul(0x9E37_79B9).rotate_left(13) ^ 0x5bd1_e995;
        0.8 + 0.4 * (v.wrapping_mul(0x2545_F491) >> 8) as f32 / (1 << 24) as f32
    };
    let side = |i: usize| if (i as u32 % w) < step { 1.0 } else { 3.0 };
    let a_raw: Vec<Vec3> = (0..g.len())
        .map(|i| Vec3::splat(side(i) * noise(i)))
        .collect();
    let a = blur(&a_raw, &g, &disc, &p.recombination());
    let ratio: Vec<Vec3> = (0..g.len()).map(|i| Vec3::splat(side(i))).collect();
    let noisy: Vec<Vec3> = (0..g.len()).map(|i| Vec3::splat(noise(i))).collect();
    let stop = Stop::SmoothedA(&a);
    let [r, s] = blur_n_stopped([ratio.clone(), noisy.clone()], &g, &disc, &p, stop);
    for y in 0..h {
        let at = |x: u32| (y * w + x) as usize;
        assert!(
            (r[at(step - 1)].x - 1.0).abs() < 1e-5,
            "{}",
            r[at(step - 1)]
        );
        assert!((r[at(step)].x - 3.0).abs() < 1e-5, "{}", r[at(step)]);
    }
    // The share of the pixels at least 8 from the borders and 18 from the step (beyond the
    // smoothing's and the walk's reach) whose walks some key stopped: their blur differs
    // from the blur without the stop.
    let plain = blur(&noisy, &g, &disc, &BlurParams { a_diff: 0.0, ..p });
    let stopped = |img: &[Vec3]| {
        let far = (0..g.len()).filter(|&i| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            x.abs_diff(step) >= 18 && (8..w - 8).contains(&x) && (8..h - 8).contains(&y)
        });
        let (count, total) = far.fold((0, 0), |(c, t), i| {
            (c + usize::from((img[i].x - plain[i].x).abs() > 1e-5), t + 1)
        });
        count as f32 / total as f32
    };
    let raw_keys: Vec<f32> = a.iter().map(|&c| unshadowed_key(c)).collect();
    let [old] = blur_n_stopped([noisy], &g, &disc, &p, Stop::Keys(&raw_keys));
    assert!(stopped(&s) < 0.05, "{}", stopped(&s));
    assert!(stopped(&old) > 0.5, "{}", stopped(&old));
}

/// A face-on plane at depth 5 s whose depths step by two units in the last place at one
/// column (rounding, not an edge), and a real step of 1% at another: at every scale s of
/// the scene's units (millimetres to kilometres) only the real step is a discontinuity.
#[test]
fn discontinuities_do_not_depend_on_the_scene_units() {
    let (w, h) = (24u32, 4u32);
    for s in [1e-3f32, 1.0, 1e3, 1e4] {
        let base = 5.0 * s;
        let two_ulps = f32::from_bits(base.to_bits() + 2);
        let n = (w * h) as usize;
        let depth: Vec<f32> = (0..n)
            .map(|i| match i as u32 % w {
                x if x < 8 => base,
                x if x < 16 => two_ulps,
                _ => 1.01 * base,
            })
            .collect();
        let position = (0..n)
            .map(|i| Vec3::new((i as u32 % w) as f32, (i as u32 / w) as f32, -1.0) * s)
            .collect();
        let g = GBuffer::from_planes((w, h), position, vec![Vec3::Z; n], depth);
        let disc = discontinuities(&g, &BlurParams::defaults());
        for (i, &d) in disc.iter().enumerate() {
            let x = i as u32 % w;
            assert_eq!(d & JUMP_X != 0, x == 15, "scale {s}, pixel {i}: {d:#b}");
        }
    }
}
