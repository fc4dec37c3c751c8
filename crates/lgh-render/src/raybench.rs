//! Ray throughput on a scene: primary, shadow (any-hit) and bounce (closest-hit) rays.

use std::time::Instant;

use glam::{Vec2, Vec3};
use lgh_core::rng::Rng;
use lgh_core::sampling::cosine_hemisphere;
use rayon::prelude::*;

use crate::world::World;

/// Measured ray rates.
#[derive(Clone, Debug, PartialEq)]
pub struct RayBench {
    /// Triangles in the BVH.
    pub triangles: usize,
    /// BVH build time (ms).
    pub bvh_build_ms: f64,
    /// Primary rays per second (camera rays through a `width` x `height` image).
    pub primary_rays_per_s: f64,
    /// Shadow rays per second (segments from visible points to random other visible points).
    pub shadow_rays_per_s: f64,
    /// Bounce rays per second (cosine-distributed closest-hit rays from visible points).
    pub bounce_rays_per_s: f64,
    /// Rays traced per kind.
    pub rays: usize,
}

/// Traces about `rays` rays of each kind and reports the rates; `bvh_build_ms` is passed
/// through from the caller, who timed [`World::new`].
#[must_use]
pub fn bench_rays(world: &World, rays: usize, bvh_build_ms: f64) -> RayBench {
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
    if points.is_empty() {
        return RayBench {
            triangles: world.accel.len(),
            bvh_build_ms,
            primary_rays_per_s: primary,
            shadow_rays_per_s: 0.0,
            bounce_rays_per_s: 0.0,
            rays: n,
        };
    }
    let m = points.len();

    let start = Instant::now();
    let blocked: usize = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::new(&[i as u64, 0x5a]);
            let (a, na) = points[i % m];
            let (b, nb) = points[(rng.next_u32() as usize) % m];
            usize::from(world.occluded_between(a, na, b, nb))
        })
        .sum();
    let shadow = n as f64 / start.elapsed().as_secs_f64();

    let start = Instant::now();
    let bounced: usize = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::new(&[i as u64, 0xb0]);
            let (a, na) = points[i % m];
            let d = cosine_hemisphere(na, rng.next_2d());
            usize::from(world.trace(world.offset(a, na, d), d).is_some())
        })
        .sum();
    let bounce = n as f64 / start.elapsed().as_secs_f64();
    std::hint::black_box((blocked, bounced));
    RayBench {
        triangles: world.accel.len(),
        bvh_build_ms,
        primary_rays_per_s: primary,
        shadow_rays_per_s: shadow,
        bounce_rays_per_s: bounce,
        rays: n,
    }
}
