//! Tests of the parent module.
use super::*;
use lgh_core::rng::Rng;

/// The filter as the module docs define it, one pixel and one tap at a time, with the
/// library exponential.
fn reference(s: &[Vec3], u: &[Vec3], g: &GBuffer, p: &AtrousParams) -> (Vec<Vec3>, Vec<Vec3>) {
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
                            + (g.position[i] - g.position[q]).length_squared() / p.p_phi;
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
    };
    (g, s, u)
}

/// The vectorised filter equals the per-pixel definition (to the accuracy of its
/// exponential, 2e-4) on a random G-buffer with holes, for steps up to past the image.
#[test]
fn the_filter_matches_its_definition() {
    let (g, s, u) = random_input(1, 37);
    let n = g.len();
    let params = AtrousParams::lgh_defaults(3.0);
    let (fs, fu) = filter_ratio_pair(&s, &u, &g, &params);
    let (rs, ru) = reference(&s, &u, &g, &params);
    for i in 0..n {
        for (a, b) in [(fs[i], rs[i]), (fu[i], ru[i])] {
            assert!(
                (a - b).abs().max_element() <= 2e-4 * b.max_element().max(0.1),
                "pixel {i}: {a} vs {b}"
            );
        }
    }
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
            ..AtrousParams::lgh_defaults(3.0)
        };
        let reused = filter_ratio_pair_with(&s, &u, &g, &params, &mut buffers);
        assert_eq!(
            reused,
            filter_ratio_pair(&s, &u, &g, &params),
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
