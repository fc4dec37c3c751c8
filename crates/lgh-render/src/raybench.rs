//! Ray throughput on a scene: primary, shadow (any-hit) and bounce (closest-hit) rays, and the
//! BVH build, for one ray tracer ([`AccelKind`]).

use std::time::Instant;

use glam::{Vec2, Vec3};
use lgh_core::rng::Rng;
use lgh_core::sampling::cosine_hemisphere;
use rayon::prelude::*;

use crate::world::World;
use crate::world::accel::{Accel, AccelError, AccelKind, BuildUse, Segment};

/// Rays per batch handed to the ray tracer by one task (the size the renderer's batches have).
const BATCH: usize = 256;

/// Measured ray rates.
#[derive(Clone, Debug, PartialEq)]
pub struct RayBench {
    /// The ray tracer.
    pub accel: AccelKind,
    /// Triangles in the BVH.
    pub triangles: usize,
    /// BVH build time for a still scene (ms, the median of the builds timed).
    pub bvh_build_ms: f64,
    /// BVH build time for a mesh rebuilt every frame (ms, the fastest build).
    pub bvh_rebuild_ms: f64,
    /// Primary rays per second (camera rays through a `width` x `height` image, one at a
    /// time).
    pub primary_rays_per_s: f64,
    /// Shadow rays per second (segments from visible points to random other visible points,
    /// in batches: [`Accel::occluded_many`]).
    pub shadow_rays_per_s: f64,
    /// The same shadow rays one at a time ([`Accel::occluded`]).
    pub shadow_single_rays_per_s: f64,
    /// Bounce rays per second (cosine-distributed closest-hit rays from visible points, in
    /// batches: [`Accel::intersect_many`]).
    pub bounce_rays_per_s: f64,
    /// Rays traced per kind.
    pub rays: usize,
}

/// The median of `runs` timings of `f` in ms.
fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// Times the BVH builds of `world`'s mesh with `kind` (`builds` of each use), then traces
/// about `rays` rays of each kind through `world` (whose BVH must be of `kind`).
///
/// # Errors
/// The ray tracer is not in this build.
pub fn bench_rays(
    world: &World,
    kind: AccelKind,
    rays: usize,
    builds: usize,
) -> Result<RayBench, AccelError> {
    let mesh = &world.scene.mesh;
    Accel::build_with(mesh, kind, BuildUse::Still)?;
    let bvh_build_ms = median_ms(builds, || {
        std::hint::black_box(Accel::build_with(mesh, kind, BuildUse::Still).ok());
    });
    let bvh_rebuild_ms = median_ms(builds, || {
        std::hint::black_box(Accel::build_with(mesh, kind, BuildUse::Rebuilt).ok());
    });

    let aspect = 16.0 / 9.0;
    let height = ((rays as f32 / aspect).sqrt().ceil() as u32).max(1);
    let width = ((rays as f32 / height as f32).ceil() as u32).max(1);
    let frame = world.scene.camera().frame(width, height);
    let n = (width * height) as usize;

    let start = Instant::now();
    let hits: Vec<Option<(Vec3, Vec3)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let px = Vec2::new(
                (i % width as usize) as f32 + 0.5,
                (i / width as usize) as f32 + 0.5,
            );
            world
                .trace(frame.origin, frame.direction(px))
                .map(|s| (s.position, s.geo_normal))
        })
        .collect();
    let primary = n as f64 / start.elapsed().as_secs_f64();
    let points: Vec<(Vec3, Vec3)> = hits.into_iter().flatten().collect();
    let mut r = RayBench {
        accel: kind,
        triangles: world.accel.len(),
        bvh_build_ms,
        bvh_rebuild_ms,
        primary_rays_per_s: primary,
        shadow_rays_per_s: 0.0,
        shadow_single_rays_per_s: 0.0,
        bounce_rays_per_s: 0.0,
        rays: n,
    };
    if points.is_empty() {
        return Ok(r);
    }
    let m = points.len();
    let shadow = |i: usize| {
        let mut rng = Rng::new(&[i as u64, 0x5a]);
        let (a, na) = points[i % m];
        let (b, nb) = points[(rng.next_u32() as usize) % m];
        world.shadow_segment(a, na, b, nb).unwrap_or_default()
    };
    let bounce = |i: usize| {
        let mut rng = Rng::new(&[i as u64, 0xb0]);
        let (a, na) = points[i % m];
        let d = cosine_hemisphere(na, rng.next_2d());
        Segment {
            origin: world.offset(a, na, d),
            dir: d,
            t_max: f32::INFINITY,
        }
    };
    let batches = n.div_ceil(BATCH);
    let range = |b: usize| b * BATCH..((b + 1) * BATCH).min(n);

    let shadow_rays: Vec<Segment> = (0..n).into_par_iter().map(shadow).collect();
    let start = Instant::now();
    let blocked: usize = (0..batches)
        .into_par_iter()
        .map(|b| {
            let mut out = [false; BATCH];
            let segs = &shadow_rays[range(b)];
            world.accel.occluded_many(segs, &mut out);
            out[..segs.len()].iter().filter(|&&o| o).count()
        })
        .sum();
    r.shadow_rays_per_s = n as f64 / start.elapsed().as_secs_f64();

    let start = Instant::now();
    let blocked_single: usize = shadow_rays
        .par_iter()
        .map(|s| usize::from(world.accel.occluded(s.origin, s.dir, s.t_max)))
        .sum();
    r.shadow_single_rays_per_s = n as f64 / start.elapsed().as_secs_f64();

    let bounce_rays: Vec<Segment> = (0..n).into_par_iter().map(bounce).collect();
    let start = Instant::now();
    let bounced: usize = (0..batches)
        .into_par_iter()
        .map(|b| {
            let mut out = [None; BATCH];
            let segs = &bounce_rays[range(b)];
            world.accel.intersect_many(segs, &mut out);
            out.iter().flatten().count()
        })
        .sum();
    r.bounce_rays_per_s = n as f64 / start.elapsed().as_secs_f64();
    std::hint::black_box((blocked, blocked_single, bounced));
    Ok(r)
}
