//! The GPU backend against the CPU: the WGSL validated by naga (no adapter needed), and, where
//! an adapter exists (lavapipe in CI), the GPU brute force against the CPU's over the same
//! VPLs.

use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::{BRUTE, BRUTE_UNSHADOWED};
use lgh_render::{Component, RenderSettings, Silent, render_frame};

mod common;
use common::{SCENES, world};

#[test]
fn every_shader_is_valid_wgsl() {
    for source in [
        lgh_gpu::brute::source(),
        lgh_gpu::rays::source(),
        lgh_gpu::lgh::source(),
        lgh_gpu::atrous::source(),
        lgh_gpu::direct::source(),
        lgh_gpu::direct::composite_source(),
        lgh_gpu::interleave::blur_source(),
        lgh_gpu::interleave::discontinuities_source(),
        lgh_gpu::interleave::keys_source(),
        lgh_gpu::ratio::ratio_source(),
        lgh_gpu::primary::source(),
        lgh_gpu::edges::source(),
    ]
    .into_iter()
    .chain(lgh_gpu::scan::sources())
    .chain(lgh_gpu::vpls::sources())
    .chain(lgh_gpu::grid::sources().into_iter().map(|(_, s)| s))
    .chain(lgh_gpu::lgh::light_table_sources())
    .chain(lgh_gpu::lgh::lookup_sources())
    .chain(lgh_gpu::bins::sources())
    .chain(lgh_gpu::fill::sources())
    {
        validate(&source);
    }
}

fn validate(source: &str) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
}

#[test]
fn the_bvh_flattens_with_every_triangle() {
    // Every triangle is in the leaves (three corners each), and the depth check passes.
    let mut scene = lgh_scene::cornell::cornell_box();
    scene
        .finish(std::path::Path::new("<built-in cornell>"))
        .expect("scene");
    let lgh_gpu::scene::FlatBvh { nodes, tris, .. } =
        lgh_gpu::scene::flatten(&scene.mesh, None).expect("flattens");
    assert_eq!(tris.len(), 3 * scene.mesh.len());
    assert!(!nodes.is_empty());
}

/// GPU `brute` equals CPU `brute` over the same VPLs within rel_rmse 0.002 (and
/// `brute-unshadowed` too), indirect light at 48x27 with 2,000 VPLs, on the default scene
/// and the three test scenes.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_brute_force_equals_the_cpu_brute_force() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    eprintln!("adapter: {}", ctx.adapter_name());
    for rel in SCENES {
        let w = world(rel);
        for (cpu, gpu) in [
            (BRUTE_UNSHADOWED, lgh_gpu::brute::BRUTE_UNSHADOWED_GPU),
            (BRUTE, lgh_gpu::brute::BRUTE_GPU),
        ] {
            let s = RenderSettings {
                method: cpu,
                width: 48,
                height: 27,
                vpls: 2000,
                component: Component::Indirect,
                ..RenderSettings::default()
            };
            let a = render_frame(&w, &s, &Silent).expect("cpu").image;
            let b = render_frame(
                &w,
                &RenderSettings {
                    method: gpu,
                    ..s.clone()
                },
                &Silent,
            )
            .expect("gpu")
            .image;
            let m = diff(&b, &a).expect("same size");
            eprintln!("{rel:?} {}: {m:?}", cpu.name());
            assert!(m.rel_rmse <= 0.002, "{rel:?} {}: {m:?}", cpu.name());
            assert!(b.pixels.iter().all(|p| p.is_finite()));
        }
    }
}

/// The same frame twice gives the same bits (no result depends on scheduling).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_brute_force_is_deterministic() {
    let w = world(None);
    let s = RenderSettings {
        method: lgh_gpu::brute::BRUTE_GPU,
        width: 32,
        height: 18,
        vpls: 500,
        ..RenderSettings::default()
    };
    let a = render_frame(&w, &s, &Silent).expect("gpu").image;
    let b = render_frame(&w, &s, &Silent).expect("gpu").image;
    assert_eq!(a.pixels, b.pixels);
}

/// A CPU twin of `shaders/bvh.wgsl`'s traversal over the flattened BVH.
fn occluded_twin(
    nodes: &[lgh_gpu::scene::GpuNode],
    tris: &[glam::Vec4],
    o: glam::Vec3,
    d: glam::Vec3,
    t_max: f32,
) -> bool {
    use glam::Vec3;
    let inv = Vec3::ONE / d;
    let entry = |n: &lgh_gpu::scene::GpuNode| {
        let t0 = (Vec3::from(n.lo) - o) * inv;
        let t1 = (Vec3::from(n.hi) - o) * inv;
        let tn = t0.min(t1).max_element().max(0.0);
        let tf = t0.max(t1).min_element().min(t_max);
        (tn <= tf).then_some(tn)
    };
    let mut stack = vec![0usize];
    if nodes.is_empty() || entry(&nodes[0]).is_none() {
        return false;
    }
    while let Some(i) = stack.pop() {
        let n = nodes[i];
        if n.count > 0 {
            for t in n.first..n.first + n.count {
                let a = tris[3 * t as usize].truncate();
                let e1 = tris[3 * t as usize + 1].truncate() - a;
                let e2 = tris[3 * t as usize + 2].truncate() - a;
                let p = d.cross(e2);
                let det = e1.dot(p);
                if det == 0.0 {
                    continue;
                }
                let s = o - a;
                let u = s.dot(p) / det;
                let q = s.cross(e1);
                let v = d.dot(q) / det;
                let tt = e2.dot(q) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 && tt < t_max {
                    return true;
                }
            }
        } else {
            for c in [n.first as usize, n.first as usize + 1] {
                if entry(&nodes[c]).is_some() {
                    stack.push(c);
                }
            }
        }
    }
    false
}

/// The flattened BVH answers as the CPU's tracer on random segments of every test scene.
#[test]
fn the_flattened_bvh_answers_as_the_cpu_tracer() {
    for rel in SCENES {
        let w = world(rel);
        let lgh_gpu::scene::FlatBvh { nodes, tris, .. } =
            lgh_gpu::scene::flatten(&w.scene.mesh, w.cutouts.as_deref()).expect("flattens");
        let (lo, hi) = w.scene.mesh.bounds();
        let mut rng = lgh_core::rng::Rng::new(&[5]);
        let mut wrong = 0;
        for _ in 0..20_000 {
            let mut p =
                || lo + (hi - lo) * glam::Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let (a, b) = (p(), p());
            let len = (b - a).length();
            let d = (b - a) / len;
            wrong +=
                usize::from(occluded_twin(&nodes, &tris, a, d, len) != w.accel.occluded(a, d, len));
        }
        assert!(wrong <= 4, "{rel:?}: {wrong} of 20000");
    }
}

/// The shadow rays of the brute force at 32 x 18 with `vpls` VPLs: every visible point to
/// every VPL.
fn brute_pairs(w: &lgh_render::World, vpls: usize) -> Vec<lgh_gpu::rays::PointPair> {
    let s = RenderSettings {
        width: 32,
        height: 18,
        vpls,
        method: BRUTE_UNSHADOWED,
        ..RenderSettings::default()
    };
    let vpls = render_frame(w, &s, &Silent).expect("frame").vpls.vpls;
    let g =
        lgh_render::passes::gbuffer::GBuffer::render(w, &w.scene.camera().frame(32, 18), 32, 18);
    (0..g.len())
        .filter(|&p| g.is_hit(p))
        .flat_map(|p| {
            let (a, na) = (g.position[p], g.geo_normal[p]);
            let vpls = &vpls;
            (0..vpls.len()).map(move |j| lgh_gpu::rays::PointPair {
                a,
                na,
                b: vpls.positions[j],
                nb: vpls.normals[j],
            })
        })
        .collect()
}

/// The GPU's traversal answers as the CPU's tracer for the shadow rays of the brute force
/// (every visible point to every VPL) on the default scene and the three test scenes.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_occlusion_agrees_with_the_cpu_tracer() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for rel in SCENES {
        let w = world(rel);
        let pairs = brute_pairs(&w, 200);
        let scene =
            lgh_gpu::GpuScene::new(ctx, &w.scene.mesh, w.cutouts.as_deref()).expect("upload");
        let gpu = lgh_gpu::rays::occluded_between(ctx, &scene, &pairs, w.ray_epsilon).expect("gpu");
        let wrong: Vec<usize> = (0..pairs.len())
            .filter(|&k| {
                gpu[k] != w.occluded_between(pairs[k].a, pairs[k].na, pairs[k].b, pairs[k].nb)
            })
            .collect();
        for &k in wrong.iter().take(3) {
            eprintln!(
                "{rel:?}: gpu {} for {:?} {:?}",
                gpu[k],
                pairs[k],
                w.shadow_segment(pairs[k].a, pairs[k].na, pairs[k].b, pairs[k].nb)
            );
        }
        assert!(
            wrong.len() * 1000 <= pairs.len(),
            "{rel:?}: {} of {} pairs disagree",
            wrong.len(),
            pairs.len()
        );
    }
}

/// The GPU's traversal answers the same in any units: the brute force's shadow rays of two
/// rooms with every length times 1e-7 get the CPU tracer's answers for the rooms in metres.
/// The triangle test refused |det| < 1e-12, an absolute bound that missed every triangle of
/// so small a scene (the GPU's brute force was black there, its light paths left no VPL).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_occlusion_does_not_depend_on_the_units() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let w = world(Some("test/two-rooms.toml"));
    let pairs = brute_pairs(&w, 100);
    let unit = 1e-7;
    let mut mesh = w.scene.mesh.clone();
    mesh.positions.iter_mut().for_each(|p| *p *= unit);
    let scene = lgh_gpu::GpuScene::new(ctx, &mesh, w.cutouts.as_deref()).expect("upload");
    let scaled: Vec<lgh_gpu::rays::PointPair> = pairs
        .iter()
        .map(|p| lgh_gpu::rays::PointPair {
            a: p.a * unit,
            b: p.b * unit,
            ..*p
        })
        .collect();
    let gpu =
        lgh_gpu::rays::occluded_between(ctx, &scene, &scaled, w.ray_epsilon * unit).expect("gpu");
    let occluded = gpu.iter().filter(|&&o| o).count();
    let wrong = (0..pairs.len())
        .filter(|&k| {
            let p = pairs[k];
            gpu[k] != w.occluded_between(p.a, p.na, p.b, p.nb)
        })
        .count();
    assert!(
        occluded > 0 && occluded < pairs.len(),
        "{occluded} of {} occluded",
        pairs.len()
    );
    assert!(
        wrong * 1000 <= pairs.len(),
        "{wrong} of {} pairs disagree",
        pairs.len()
    );
}

/// The GPU's a-trous filter of S and U equals the CPU's (`filter_ratio_pair`) within rel_rmse
/// 1e-3 (the CPU's exponential is a polynomial good to 1e-4), on noisy estimates over the
/// G-buffers of the default scene and two-rooms, 5 passes, without and with the weight on
/// the unshadowed sums A (over two decades, a_phi 0.05).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_atrous_equals_the_cpu_filter() {
    use glam::Vec3;
    use lgh_render::denoise::atrous::{AtrousParams, filter_ratio_pair};
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for scene in [None, Some("test/two-rooms.toml")] {
        let w = world(scene);
        let (width, height) = (80, 45);
        let g = lgh_render::passes::gbuffer::GBuffer::render(
            &w,
            &w.scene.camera().frame(width, height),
            width,
            height,
        );
        let mut rng = lgh_core::rng::Rng::new(&[11]);
        let u: Vec<Vec3> = (0..g.len())
            .map(|_| Vec3::new(0.2, 0.3, 0.1) + 0.5 * rng.next_f32())
            .collect();
        let s: Vec<Vec3> = u
            .iter()
            .map(|&u| {
                u * if rng.next_f32() < 0.6 {
                    rng.next_f32()
                } else {
                    0.0
                }
            })
            .collect();
        let a: Vec<Vec3> = (0..g.len())
            .map(|_| Vec3::splat(10f32.powf(2.0 * rng.next_f32())))
            .collect();
        for (a, a_phi) in [(None, 0.0), (Some(&a[..]), 0.05)] {
            let params = AtrousParams {
                a_phi,
                ..AtrousParams::lgh_defaults(w.radius)
            };
            let (cs, cu) = filter_ratio_pair(&s, &u, a, &g, &params);
            let (mut gs, mut gu) = (s.clone(), u.clone());
            lgh_gpu::atrous::filter_ratio_pair(ctx, &mut gs, &mut gu, a, &g, &params).expect("gpu");
            let rel_rmse = |a: &[Vec3], b: &[Vec3]| {
                let num: f64 = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| f64::from((*x - *y).length_squared()))
                    .sum();
                let den: f64 = b.iter().map(|y| f64::from(y.length_squared())).sum();
                (num / den).sqrt()
            };
            let (es, eu) = (rel_rmse(&gs, &cs), rel_rmse(&gu, &cu));
            eprintln!("{scene:?}, a_phi {a_phi}: S {es:e}, U {eu:e}");
            assert!(
                es <= 1e-3 && eu <= 1e-3,
                "{scene:?}, a_phi {a_phi}: S {es}, U {eu}"
            );
            // The filter did something: the noisy S changed.
            assert!(rel_rmse(&gs, &s) > 0.05);
        }
    }
}

/// The viewer's mapping to GPU methods: lgh at its default estimate goes to the GPU; with a
/// shadow estimate the GPU loop does not run (the viewer's U key: the paper's), or a method
/// not ported, the frame stays on the CPU (`None`); without shadow samples any estimate runs.
#[test]
fn frames_map_to_gpu_methods_where_the_gpu_runs_their_settings() {
    use lgh_render::methods::lgh::{Estimator, LGH, ShadowTarget};
    use lgh_render::methods::slc::SLC;
    let mut s = RenderSettings::default();
    assert_eq!(s.method, LGH);
    assert_eq!(lgh_gpu::gpu_method_for(&s), Some(lgh_gpu::lgh::LGH_GPU));
    (s.lgh.estimator, s.lgh.shadow_target) = (Estimator::Paper, ShadowTarget::Centroid);
    assert_eq!(lgh_gpu::gpu_method_for(&s), None);
    s.shadows.samples = Some(0);
    assert_eq!(lgh_gpu::gpu_method_for(&s), Some(lgh_gpu::lgh::LGH_GPU));
    s.method = SLC;
    assert_eq!(lgh_gpu::gpu_method_for(&s), None);
    s.method = BRUTE;
    assert_eq!(lgh_gpu::gpu_method_for(&s), Some(lgh_gpu::brute::BRUTE_GPU));
}

/// The context's G-buffer cache: a G-buffer of the same view, or of an unknown view with
/// the same planes, gives the uploaded buffer again; one of an unknown view differing in
/// one pixel's albedo (code that changes the planes forgets the view), or of another size,
/// gives a new upload. And an upload larger than one parallel piece, not a whole number of
/// them, reads back as it went up.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn uploads_arrive_whole_and_the_gbuffer_is_reused_only_while_unchanged() {
    // A context of its own: the tests beside this one upload their G-buffers to the shared.
    let ctx = &lgh_gpu::GpuContext::new().expect("an adapter");
    let w = world(None);
    let camera = w.scene.camera().frame(40, 30);
    let g = lgh_render::passes::gbuffer::GBuffer::render(&w, &camera, 40, 30);
    assert!(g.view.is_some());
    let a = ctx.gbuffer(&g).expect("upload");
    let b = ctx.gbuffer(&g.clone()).expect("upload");
    assert!(std::sync::Arc::ptr_eq(&a, &b), "same view, same buffer");
    let mut unknown = g.clone();
    unknown.view = None;
    let b = ctx.gbuffer(&unknown).expect("upload");
    assert!(std::sync::Arc::ptr_eq(&a, &b), "same planes, same buffer");
    let mut changed = unknown.clone();
    changed.albedo[517].x += 0.25;
    let c = ctx.gbuffer(&changed).expect("upload");
    assert!(
        !std::sync::Arc::ptr_eq(&a, &c),
        "a changed pixel is uploaded"
    );
    let smaller = lgh_render::passes::gbuffer::GBuffer::render(&w, &camera, 40, 29);
    let d = ctx.gbuffer(&smaller).expect("upload");
    assert!(!std::sync::Arc::ptr_eq(&c, &d), "a new size is uploaded");

    let data: Vec<u32> = (0..700_001u32)
        .map(|i| i.wrapping_mul(2_654_435_761))
        .collect();
    let up = ctx.upload("upload test", &data).expect("upload");
    let mut batch = lgh_gpu::Batch::new(ctx);
    batch
        .read(up.buffer(), 4 * data.len() as u64)
        .expect("read");
    let (reads, _) = batch.finish().expect("gpu");
    let back: &[u32] = bytemuck::cast_slice(&reads[0]);
    assert_eq!(&back[..data.len()], &data[..]);
}
