//! Tests of the parent module.
use super::*;
use lgh_core::rng::Rng;

/// The filter as the module docs define it, one pixel and one tap at a time, with the
/// library exponential.
fn reference(
    s: &[Vec3],
    u: &[Vec3],
    a: Option<&[Vec3]>,
    g: &GBuffer,
    p: &AtrousParams,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let key = |i: usize| a.map_or(0.0, |a| unshadowed_key(a[i]));
    let (w, h) = (g.width as i64, g.height as i64);
    let (mut s, mut u) = (s.to_vec(), u.to_vec());
    for pass in 0..p.passes {
        let step = 1i64 << pass;
        let inv_c = 4f32.powi(pass as i32) / p.c_phi;
        let (mut s2, mut u2) = (s.clone(), u.clone());
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if !g.is_hit(i) {
                    continue;
                }
                let (mut ss, mut uu, mut wsum) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
                for (j, hy) in H1.iter().enumerate() {
                    for (k, hx) in H1.iter().enumerate() {
                        let (qx, qy) = (x + (k as i64 - 2) * step, y + (j as i64 - 2) * step);
                        if qx < 0 || qy < 0 || qx >= w || qy >= h {
                            continue;
                        }
                        let q = (qy * w + qx) as usize;
                        if !g.is_hit(q) {
                            continue;
                        }
                        let dc = filter_guide(s[i], u[i]) - filter_guide(s[q], u[q]);
                        let e = dc * dc * inv_c
                            + (g.normal[i] - g.normal[q]).length_squared() / p.n_phi
                            + (g.position[i] - g.position[q]).length_squared() / p.p_phi
                            + if p.a_phi > 0.0 {
                                (key(i) - key(q)).powi(2) / p.a_phi
                            } else {
                                0.0
                            };
                        let wt = hx * hy * (-e).exp();
                        ss += wt * s[q];
                        uu += wt * u[q];
                        wsum += wt;
                    }
                }
                s2[i] = ss / wsum;
                u2[i] = uu / wsum;
            }
        }
        (s, u) = (s2, u2);
    }
    (s, u)
}

/// A random G-buffer of `w` x 23 pixels with holes (about 10 % see nothing), with S and
/// U images (S a random mix of 0 and U per channel).
fn random_input(seed: u64, w: u32) -> (GBuffer, Vec<Vec3>, Vec<Vec3>) {
    let h = 23u32;
    let n = (w * h) as usize;
    let mut rng = Rng::new(&[3, seed]);
    let mut f = || rng.next_f32();
    let mut depth = vec![1.0f32; n];
    let (mut position, mut normal) = (vec![Vec3::ZERO; n], vec![Vec3::Z; n]);
    let (mut s, mut u) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    for i in 0..n {
        let (x, y) = ((i % w as usize) as f32, (i / w as usize) as f32);
        if f() < 0.1 {
            depth[i] = f32::INFINITY;
        }
        position[i] = Vec3::new(x * 0.1, y * 0.1, if x > 20.0 { 1.0 } else { 0.0 }) + f() * 0.05;
        normal[i] = (Vec3::new(f(), f(), f()) - 0.5 + Vec3::Z).normalize();
        u[i] = Vec3::new(f(), f(), f()) + 0.1;
        s[i] = u[i] * Vec3::new(f(), f(), f()).round();
    }
    let g = GBuffer {
        width: w,
        height: h,
        position,
        normal,
        geo_normal: vec![Vec3::Z; n],
        albedo: vec![Vec3::ONE; n],
        depth,
        emission: vec![Vec3::ZERO; n],
        view: None,
        deferred: Default::default(),
    };
    (g, s, u)
}

/// The vectorised filter equals the per-pixel definition (to the accuracy of its
/// exponential, 2e-4) on a random G-buffer with holes, for steps up to past the image.
/// With the weight on the unshadowed sums too (random sums over two decades).
#[test]
fn the_filter_matches_its_definition() {
    let (g, s, u) = random_input(1, 37);
    let n = g.len();
    let mut rng = Rng::new(&[4]);
    let a: Vec<Vec3> = (0..n)
        .map(|_| Vec3::splat(10f32.powf(2.0 * rng.next_f32())))
        .collect();
    for (a, a_phi) in [(None, 0.0), (Some(&a[..]), 0.5)] {
        let params = AtrousParams {
            a_phi,
            ..AtrousParams::lgh_defaults(3.0)
        };
        let (fs, fu) = filter_ratio_pair(&s, &u, a, &g, &params);
        let (rs, ru) = reference(&s, &u, a, &g, &params);
        for i in 0..n {
            for (x, y) in [(fs[i], rs[i]), (fu[i], ru[i])] {
                assert!(
                    (x - y).abs().max_element() <= 2e-4 * y.max_element().max(0.1),
                    "a_phi {a_phi}, pixel {i}: {x} vs {y}"
                );
            }
        }
    }
}

/// The weight on the unshadowed sums keeps a ratio where A changes: a flat wall whose left
/// half has A (and U) 20 times the right half's (the pixels beside a room's corner) and a
/// true ratio of 0.7 there against 0.9 on the right, each pixel's S the mean of 16 samples
/// (U or 0: what the interleaving blur gathers). Without w_a the heavy taps of the left half
/// pull the ratio of the right half's edge towards 0.7 (D(S) / D(U) weighs taps by U). Over
/// the 4 columns each side of the boundary the filtered ratios are at least 3 times closer
/// to the truth with w_a (a_phi 0.01, lgh's default) than without (measured: 0.002 against
/// 0.10).
#[test]
fn the_unshadowed_weight_keeps_the_ratio_where_a_changes() {
    let (w, h) = (64u32, 32u32);
    let n = (w * h) as usize;
    let mut rng = Rng::new(&[5]);
    let left = |i: usize| (i % w as usize) < w as usize / 2;
    let a: Vec<Vec3> = (0..n)
        .map(|i| Vec3::splat(if left(i) { 20.0 } else { 1.0 }))
        .collect();
    let u = a.clone();
    let s: Vec<Vec3> = (0..n)
        .map(|i| {
            let p = if left(i) { 0.7 } else { 0.9 };
            let hits = (0..16).filter(|_| rng.next_f32() < p).count();
            u[i] * (hits as f32 / 16.0)
        })
        .collect();
    let g = GBuffer {
        width: w,
        height: h,
        position: (0..n)
            .map(|i| Vec3::new((i % w as usize) as f32, (i / w as usize) as f32, 0.0) * 0.01)
            .collect(),
        normal: vec![Vec3::Z; n],
        geo_normal: vec![Vec3::Z; n],
        albedo: vec![Vec3::ONE; n],
        depth: vec![1.0; n],
        emission: vec![Vec3::ZERO; n],
        view: None,
        deferred: Default::default(),
    };
    // Mean |ratio - true ratio| over the 4 columns each side of the boundary.
    let error = |a_phi: f32| {
        let params = AtrousParams {
            a_phi,
            ..AtrousParams::lgh_defaults(3.0)
        };
        let (fs, fu) = filter_ratio_pair(&s, &u, Some(&a), &g, &params);
        let cols = (w / 2 - 4) as usize..(w / 2 + 4) as usize;
        let (mut sum, mut count) = (0.0, 0.0);
        for y in 0..h as usize {
            for x in cols.clone() {
                let i = y * w as usize + x;
                let truth = if left(i) { 0.7 } else { 0.9 };
                sum += (fs[i].x / fu[i].x - truth).abs();
                count += 1.0;
            }
        }
        sum / count
    };
    let (with, without) = (error(0.01), error(0.0));
    assert!(3.0 * with <= without, "with w_a {with}, without {without}");
}

/// Reused buffers give the same result, bit for bit, as fresh ones, after an image with
/// other holes, a narrower image of the same padded row length, and other pass counts
/// (other padding).
#[test]
fn reused_buffers_do_not_change_the_result() {
    let mut buffers = AtrousBuffers::default();
    for (seed, w, passes) in [(1, 37, 5), (2, 37, 5), (3, 35, 5), (4, 37, 3), (5, 37, 5)] {
        let (g, s, u) = random_input(seed, w);
        let params = AtrousParams {
            passes,
            a_phi: 0.1,
            ..AtrousParams::lgh_defaults(3.0)
        };
        let reused = filter_ratio_pair_with(&s, &u, Some(&u), &g, &params, &mut buffers);
        assert_eq!(
            reused,
            filter_ratio_pair(&s, &u, Some(&u), &g, &params),
            "seed {seed}"
        );
    }
}

#[test]
fn exp_neg_is_close_to_exp() {
    let mut e = 0.0f32;
    while e < 60.0 {
        let (a, b) = (exp_neg(e), (-e).exp());
        assert!((a - b).abs() <= 2e-4 * b + 1e-30, "{e}: {a} vs {b}");
        e += 0.013;
    }
    assert!(exp_neg(100.0) < 1e-30);
    assert!(exp_neg(f32::NAN) < 1e-30);
    assert!(exp_neg(f32::INFINITY) < 1e-30);
}
