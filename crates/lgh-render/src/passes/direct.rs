//! Direct lighting from the primary lights, with exact shadow rays.
//!
//! Point, spot and directional lights are evaluated exactly (one shadow ray each). Area lights
//! are estimated with `area_samples` points per pixel, chosen in proportion to radiance x area
//! and then uniformly on the triangle (an unbiased estimator of the area integral).

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use lgh_core::rng::Rng;
use lgh_scene::Light;

use crate::passes::gbuffer::GBuffer;
use crate::passes::per_pixel;
use crate::progress::Progress;
use crate::world::World;

/// Random-stream tag of the direct-lighting pass.
const STREAM_DIRECT: u64 = 0xd1;

/// Irradiance (RGB, W/m^2) arriving at surface point `p` (shading normal `n`, geometric normal
/// `ng`) directly from the primary lights, shadows included.
#[must_use]
pub fn direct_irradiance(
    world: &World,
    p: Vec3,
    n: Vec3,
    ng: Vec3,
    rng: &mut Rng,
    area_samples: u32,
) -> Vec3 {
    let mut e = Vec3::ZERO;
    for light in &world.lights.punctual {
        match light {
            Light::Point {
                position,
                intensity,
            }
            | Light::Spot {
                position,
                intensity,
                ..
            } => {
                let d = *position - p;
                let d2 = d.length_squared();
                let w = d / d2.sqrt();
                let cos = n.dot(w);
                if cos <= 0.0 || ng.dot(w) <= 0.0 {
                    continue;
                }
                let f = light.falloff(-w);
                if f <= 0.0 {
                    continue;
                }
                let o = world.offset(p, ng, w);
                let len = (*position - o).length();
                if !world.accel.occluded(o, w, len * (1.0 - 1e-4)) {
                    e += *intensity * (f * cos / d2);
                }
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                let w = -*direction;
                let cos = n.dot(w);
                if cos <= 0.0 || ng.dot(w) <= 0.0 {
                    continue;
                }
                let o = world.offset(p, ng, w);
                if !world.accel.occluded(o, w, 4.0 * world.radius) {
                    e += *irradiance * cos;
                }
            }
        }
    }
    if area_samples > 0 && !world.lights.emitters.is_empty() {
        let mut sum = Vec3::ZERO;
        for _ in 0..area_samples {
            let Some(s) = world
                .lights
                .sample_emitter_point(rng.next_f32(), rng.next_2d())
            else {
                break;
            };
            let d = s.position - p;
            let d2 = d.length_squared();
            let w = d / d2.sqrt();
            let cos_x = n.dot(w);
            let cos_l = -s.normal.dot(w);
            if cos_x <= 0.0 || cos_l <= 0.0 || ng.dot(w) <= 0.0 {
                continue;
            }
            if !world.occluded_between(p, ng, s.position, s.normal) {
                sum += s.radiance * (cos_x * cos_l / (d2 * s.pdf_area));
            }
        }
        e += sum / area_samples as f32;
    }
    e
}

/// Direct-lighting radiance towards the camera for every pixel (albedo / pi x irradiance).
#[must_use]
pub fn render_direct(
    world: &World,
    g: &GBuffer,
    seed: u64,
    area_samples: u32,
    progress: &dyn Progress,
) -> Vec<Vec3> {
    progress.begin("direct", u64::from(g.height));
    let out = per_pixel(g.len(), g.width as usize, progress, |i| {
        if !g.is_hit(i) {
            return Vec3::ZERO;
        }
        let mut rng = Rng::new(&[seed, i as u64, STREAM_DIRECT]);
        let e = direct_irradiance(
            world,
            g.position[i],
            g.normal[i],
            g.geo_normal[i],
            &mut rng,
            area_samples,
        );
        g.albedo[i] * FRAC_1_PI * e
    });
    progress.end();
    out
}
