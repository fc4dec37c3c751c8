//! One frame, pass by pass: the recipe the command line and library users follow.
//!
//! ```text
//! scene --World::new--> BVH + light tables
//!        camera --GBuffer::render--> G-buffer (position, normal, albedo, depth, emission)
//!        lights --generate_vpls--> VPLs (light tracing)
//!        G-buffer + lights --render_direct--> direct radiance (exact shadow rays)
//!        G-buffer + VPLs --method--> indirect radiance
//!        emission + direct + indirect --> image (the chosen component)
//! ```

use std::time::Instant;

use glam::Vec3;

use crate::brute::render_brute;
use crate::direct::render_direct;
use crate::gbuffer::GBuffer;
use crate::image::Image;
use crate::progress::Progress;
use crate::vpl_gen::{VplSet, generate_vpls};
use crate::world::World;

/// How the indirect light (the VPLs' contribution) is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Every pixel sums every VPL with an exact shadow ray (the reference).
    Brute,
    /// Every pixel sums every VPL, no shadow rays.
    BruteUnshadowed,
}

impl Method {
    /// The name used on the command line and in statistics.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Brute => "brute",
            Method::BruteUnshadowed => "brute-unshadowed",
        }
    }
}

/// Which part of the radiance the output image holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Component {
    /// Emission + direct + indirect.
    All,
    /// Emission + direct light from the primary lights.
    Direct,
    /// Indirect light only (the VPLs), to compare methods on what differs between them.
    Indirect,
}

/// Everything that defines a frame besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Number of VPLs to generate (at least; whole light paths).
    pub vpls: usize,
    /// Maximum VPLs per light path (indirect bounces represented).
    pub bounces: u32,
    /// Seed of every random choice.
    pub seed: u64,
    /// Shadow-ray samples per pixel for area lights in the direct pass.
    pub area_samples: u32,
    /// Indirect-lighting method.
    pub method: Method,
    /// What the output image holds.
    pub component: Component,
    /// eps of the 1/(d^2 + eps^2) clamp, as a fraction of the scene's bounding-sphere radius
    /// (LGH design notes 4.3: 0.01).
    pub clamp_fraction: f32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            vpls: 10_000,
            bounces: 3,
            seed: 0,
            area_samples: 16,
            method: Method::Brute,
            component: Component::All,
            clamp_fraction: 0.01,
        }
    }
}

/// Wall time of each pass, in milliseconds, in the order they ran.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timings(pub Vec<(String, f64)>);

impl Timings {
    /// Runs `f`, records its time under `name` and returns its result.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.0
            .push((name.to_string(), start.elapsed().as_secs_f64() * 1e3));
        out
    }

    /// The time recorded under `name`.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, t)| *t)
    }
}

/// A rendered frame with its parts.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The requested component (see [`RenderSettings::component`]).
    pub image: Image,
    /// Emitted radiance seen directly.
    pub emission: Image,
    /// Direct lighting.
    pub direct: Image,
    /// Indirect lighting from the VPLs.
    pub indirect: Image,
    /// The VPLs used.
    pub vpls: VplSet,
    /// Per-pass times: `gbuffer`, `vpl_generation`, `direct`, `indirect`, `total`.
    pub timings: Timings,
}

/// Renders one frame of `world` (see the module docs for the passes).
#[must_use]
pub fn render_frame(world: &World, s: &RenderSettings, progress: &dyn Progress) -> Frame {
    let start = Instant::now();
    let mut t = Timings::default();
    let (w, h) = (s.width, s.height);
    let camera = world.scene.camera().frame(w, h);
    let g = t.time("gbuffer", || GBuffer::render(world, &camera, w, h));
    let vpls = t.time("vpl_generation", || {
        generate_vpls(world, s.vpls, s.bounces, s.seed)
    });
    let direct = t.time("direct", || {
        render_direct(world, &g, s.seed, s.area_samples, progress)
    });
    let eps = s.clamp_fraction * world.radius;
    let indirect = t.time("indirect", || match s.method {
        Method::Brute => render_brute(world, &g, &vpls.vpls, eps, true, progress),
        Method::BruteUnshadowed => render_brute(world, &g, &vpls.vpls, eps, false, progress),
    });
    let emission = Image::from_pixels(w, h, g.emission.clone());
    let direct = Image::from_pixels(w, h, direct);
    let indirect = Image::from_pixels(w, h, indirect);
    let image = Image::from_pixels(
        w,
        h,
        (0..g.len())
            .map(|i| {
                let e = emission.pixels[i];
                match s.component {
                    Component::All => e + direct.pixels[i] + indirect.pixels[i],
                    Component::Direct => e + direct.pixels[i],
                    Component::Indirect => indirect.pixels[i],
                }
            })
            .collect::<Vec<Vec3>>(),
    );
    t.0.push(("total".into(), start.elapsed().as_secs_f64() * 1e3));
    Frame {
        image,
        emission,
        direct,
        indirect,
        vpls,
        timings: t,
    }
}
