//! Progressive path tracing with many area lights (Tokuyoshi & Harada 2016, section 5), and
//! its baselines.
//!
//! Diffuse surfaces; at every path vertex x the direct light comes from one sampled emissive
//! triangle (next-event estimation), combined with BSDF (cosine) sampling by multiple
//! importance sampling (power heuristic). One sample per pixel and pass; each pass is one
//! "frame" of the paper with its own random light ranges.
//!
//! Light selection at x, [`LightSampling`]:
//! - **Slc** (Algorithm 2 with Algorithm 3): per frame every triangle light gets
//!   alpha_i = 2 pi epsilon_max / (E L_i A_i) (Eq. 7), xi_i from TEA and the range r_i of
//!   Eq. 3 (f = 1/l^2); the bounding sphere tree ([`lgh_core::sphere_tree`]) is refitted.
//!   At x the tree yields the m lights whose influence sphere holds x; reservoir sampling keeps
//!   k of them, each with probability min(k/m, 1). One of those is resampled with
//!   q(i) = g_i / sum g (Eq. 8, importance g_i of Eq. 9), a point x_i uniformly on it, and the
//!   sample counts only if |x_i - x| < r_i, with density
//!   p_i(|x_i - x|) min(k/m, 1) q(i) / A_i (Eq. 10). Unbiased over frames.
//! - **Uniform**: a light uniformly among all N, a point uniformly on it: density 1/(N A_i).
//! - **Clamped**: as Slc with fixed ranges from the error bound (Appendix A) and no p_i in the
//!   density; light beyond the range is lost (biased darker).
//!
//! In Eq. 9 the second cosine, max over the triangle's vertices of w_{i,v} . n, is read as the
//! receiver's cosine bound (n = the shading normal at x); the paper's text writes n_i there.
//!
//! MIS: the weights of both strategies use one proxy light density that does not depend on
//! the light's own random range nor on the reservoir's choices, p^_i(y) = p_i(l) g_i / G / A_i
//! with G the importance summed over all m overlapping lights (plus g_i if light i does not
//! overlap x this frame). Weights built from it sum to one for every y whatever the random
//! state, which keeps the combination unbiased; the actual (conditional) density, Eq. 10,
//! stays in the light estimator's denominator. (Weights from the conditional density would
//! give a BSDF hit full weight whenever the light's roulette failed, and count that light
//! twice on average: 1 + w (1 - p_i) instead of 1.)

use std::f32::consts::FRAC_1_PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use lgh_core::light_range::{
    alpha_area, clamped_range, keep_probability, light_xi, stochastic_range,
};
use lgh_core::reservoir::UniformReservoir;
use lgh_core::rng::{Rng, hash};
use lgh_core::sampling::{cosine_hemisphere, uniform_triangle};
use lgh_core::sphere_tree::SphereTree;
use rayon::prelude::*;

use crate::memory::FrameMemory;
use crate::methods::{Illumination, IndirectMethod, Method, MethodInputs, MethodOutput};
use crate::passes::gbuffer::GBuffer;
use crate::progress::Progress;
use crate::settings::{ErrorBound, RenderError};
use crate::world::World;
use crate::world::lights::Emitter;

/// Random-stream tag of the path tracer.
const STREAM_PT: u64 = 0x97;

/// How a light is chosen at a path vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightSampling {
    /// Stochastic light culling with reservoir sampling and resampled importance sampling.
    Slc,
    /// Uniformly among all emissive triangles.
    Uniform,
    /// Light culling with clamped ranges (biased).
    Clamped,
}

/// Settings of the path tracer. Its error bound and exposure are the shared
/// [`crate::settings::RenderSettings::error_bound`] (default [`DEFAULT_ERROR_BOUND`]) and
/// [`crate::settings::RenderSettings::exposure`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct PtSettings {
    /// pt-*: samples (passes) per pixel; every pass draws new light ranges.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = PtSettings::default().spp))]
    pub spp: u32,
    /// Longest path in bounces after the camera hit.
    #[cfg_attr(feature = "clap", arg(skip = PtSettings::default().max_depth))]
    pub max_depth: u32,
    /// Lights kept by reservoir sampling per shading point (k; the paper uses 8 and 32).
    #[cfg_attr(feature = "clap", arg(skip = PtSettings::default().k))]
    pub k: usize,
}

impl Default for PtSettings {
    fn default() -> Self {
        Self {
            spp: 16,
            max_depth: 5,
            k: 8,
        }
    }
}

/// The error bound epsilon_max of the path tracer's light ranges when none is set (the
/// paper's 0.125 for area lights).
pub const DEFAULT_ERROR_BOUND: f32 = 0.125;

/// What the path tracer returns.
#[derive(Clone, Debug, Default)]
struct PtOutput {
    /// Reflected radiance towards the camera (every bounce; the camera-visible emission is
    /// in the G-buffer).
    pub radiance: Vec<Vec3>,
    /// Mean number of lights whose influence sphere held a shading point (m), over all NEE
    /// queries.
    pub avg_overlapping: f64,
}

/// The triangle lights prepared for sampling.
struct Lights<'a> {
    emitters: &'a [Emitter],
    /// L_i A_i, largest channel.
    power: Vec<f32>,
    /// Emitter index of each mesh triangle (u32::MAX: not an emitter).
    of_triangle: Vec<u32>,
    tree: SphereTree,
    /// rho_i: radius around the centroid that holds triangle i.
    extent: Vec<f32>,
    /// Range r_i of the current frame.
    range: Vec<f32>,
    alpha: Vec<f32>,
}

impl<'a> Lights<'a> {
    fn new(world: &'a World) -> Self {
        let emitters = &world.lights.emitters[..];
        let mut of_triangle = vec![u32::MAX; world.accel.len()];
        for (i, e) in emitters.iter().enumerate() {
            if let Some(slot) = of_triangle.get_mut(e.triangle as usize) {
                *slot = i as u32;
            }
        }
        let centres: Vec<Vec3> = emitters.iter().map(centroid).collect();
        let extent: Vec<f32> = emitters
            .iter()
            .zip(&centres)
            .map(|(e, &c)| {
                [e.v0, e.v0 + e.e1, e.v0 + e.e2]
                    .iter()
                    .map(|v| (*v - c).length())
                    .fold(0.0, f32::max)
            })
            .collect();
        Self {
            emitters,
            power: emitters
                .iter()
                .map(|e| e.radiance.max_element() * e.area)
                .collect(),
            of_triangle,
            tree: SphereTree::build(&centres, &extent),
            extent,
            range: vec![f32::INFINITY; emitters.len()],
            alpha: vec![0.0; emitters.len()],
        }
    }

    /// The ranges of frame `frame` and the refitted tree.
    fn set_frame(&mut self, mode: LightSampling, s: ErrorBound, frame: u32) {
        let n = self.emitters.len();
        match mode {
            LightSampling::Uniform => {}
            LightSampling::Slc => {
                let (alpha, range): (Vec<f32>, Vec<f32>) = (0..n)
                    .into_par_iter()
                    .map(|i| {
                        let a = alpha_area(s.epsilon_max, s.exposure, self.power[i], 1.0);
                        (a, stochastic_range(a, light_xi(i as u32, frame), 0.0))
                    })
                    .unzip();
                self.alpha = alpha;
                self.range = range;
                self.tree.refit(&self.range);
            }
            LightSampling::Clamped => {
                self.range = (0..n)
                    .map(|i| clamped_range(s.epsilon_max, s.exposure, n, self.power[i], 0.0))
                    .collect();
                self.tree.refit(&self.range);
            }
        }
    }
}

fn centroid(e: &Emitter) -> Vec3 {
    e.v0 + (e.e1 + e.e2) / 3.0
}

/// The lights a shading point may sample: up to k from reservoir sampling, with their
/// importance g_i, out of m overlapping ones.
struct Candidates {
    ids: Vec<u32>,
    g: Vec<f32>,
    g_sum: f32,
    /// Selection probability of a listed light before resampling: min(k/m, 1).
    keep: f32,
    m: usize,
    /// Importance summed over all m overlapping lights (for the MIS proxy density).
    g_all: f32,
}

/// Importance g_i of Eq. 9 (see the module docs for the receiver cosine).
fn importance(e: &Emitter, power: f32, x: Vec3, n: Vec3) -> f32 {
    let c = centroid(e);
    let to_c = c - x;
    let d2 = to_c.length_squared().max(1e-12);
    let cos_l = (-to_c.dot(e.normal)).max(0.0) / d2.sqrt();
    let cos_x = [e.v0, e.v0 + e.e1, e.v0 + e.e2]
        .iter()
        .map(|v| (*v - x).normalize_or_zero().dot(n))
        .fold(0.0, f32::max);
    power * cos_l * cos_x / d2
}

impl Candidates {
    fn gather(
        lights: &Lights,
        mode: LightSampling,
        k: usize,
        x: Vec3,
        n: Vec3,
        rng: &mut Rng,
    ) -> Self {
        let mut res = UniformReservoir::new(k);
        let mut g_all = 0.0;
        if mode != LightSampling::Uniform {
            // Algorithm 3: keep each of the m overlapping lights with probability k/m.
            lights.tree.for_each_overlapping(x, |i| {
                g_all += importance(&lights.emitters[i], lights.power[i], x, n);
                res.offer(i as u32, rng.next_f32());
            });
        }
        let (m, keep) = (res.seen(), res.keep_probability());
        let ids = res.items;
        let g: Vec<f32> = ids
            .iter()
            .map(|&i| importance(&lights.emitters[i as usize], lights.power[i as usize], x, n))
            .collect();
        let g_sum = g.iter().sum();
        Self {
            ids,
            g,
            g_sum,
            keep,
            m,
            g_all,
        }
    }

    /// The MIS proxy area density of point `y` on emitter `e` seen from (x, n) (module docs).
    fn mis_pdf_area(
        &self,
        lights: &Lights,
        mode: LightSampling,
        e: usize,
        x: Vec3,
        n: Vec3,
        y: Vec3,
    ) -> f32 {
        let em = &lights.emitters[e];
        match mode {
            LightSampling::Uniform => 1.0 / (lights.emitters.len() as f32 * em.area),
            LightSampling::Slc | LightSampling::Clamped => {
                let l2 = (y - x).length_squared();
                let reach = lights.extent[e] + lights.range[e];
                let overlaps = (x - centroid(em)).length_squared() < reach * reach;
                let g = importance(em, lights.power[e], x, n);
                let total = self.g_all + if overlaps { 0.0 } else { g };
                if total <= 0.0 {
                    return 0.0;
                }
                let p_range = match mode {
                    LightSampling::Slc => keep_probability(lights.alpha[e], l2, 0.0),
                    _ => f32::from(u8::from(l2 < lights.range[e] * lights.range[e])),
                };
                p_range * g / total / em.area
            }
        }
    }

    /// Area density of light sampling at point `y` on emitter `e` (distance^2 `l2` from x),
    /// given this state.
    fn pdf_area(&self, lights: &Lights, mode: LightSampling, e: usize, l2: f32) -> f32 {
        let area = lights.emitters[e].area;
        match mode {
            LightSampling::Uniform => 1.0 / (lights.emitters.len() as f32 * area),
            LightSampling::Slc | LightSampling::Clamped => {
                if l2 >= lights.range[e] * lights.range[e] || self.g_sum <= 0.0 {
                    return 0.0;
                }
                let Some(pos) = self.ids.iter().position(|&i| i as usize == e) else {
                    return 0.0;
                };
                let q = self.g[pos] / self.g_sum;
                let p_keep = if mode == LightSampling::Slc {
                    keep_probability(lights.alpha[e], l2, 0.0)
                } else {
                    1.0
                };
                p_keep * self.keep * q / area
            }
        }
    }

    /// Samples a light and a point on it: (emitter, point).
    fn sample(&self, lights: &Lights, mode: LightSampling, rng: &mut Rng) -> Option<(usize, Vec3)> {
        let n = lights.emitters.len();
        let e = match mode {
            LightSampling::Uniform => ((rng.next_f32() * n as f32) as usize).min(n.checked_sub(1)?),
            LightSampling::Slc | LightSampling::Clamped => {
                if self.g_sum <= 0.0 {
                    return None;
                }
                let u = rng.next_f32() * self.g_sum;
                let mut acc = 0.0;
                let mut pick = self.ids.len() - 1;
                for (j, &g) in self.g.iter().enumerate() {
                    acc += g;
                    if u < acc {
                        pick = j;
                        break;
                    }
                }
                self.ids[pick] as usize
            }
        };
        let em = &lights.emitters[e];
        let b = uniform_triangle(Vec2::new(rng.next_f32(), rng.next_f32()));
        Some((e, em.v0 + em.e1 * b.x + em.e2 * b.y))
    }
}

/// Power heuristic weight of a sample with density `a` against `b` (same measure).
fn mis(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// One path from the camera hit of pixel `i`; returns the reflected radiance.
#[allow(clippy::too_many_arguments)]
fn trace_path(
    world: &World,
    lights: &Lights,
    mode: LightSampling,
    s: &PtSettings,
    g: &GBuffer,
    i: usize,
    rng: &mut Rng,
    overlapping: &mut u64,
    queries: &mut u64,
) -> Vec3 {
    let (mut x, mut n, mut ng, mut albedo) =
        (g.position[i], g.normal[i], g.geo_normal[i], g.albedo[i]);
    let mut throughput = Vec3::ONE;
    let mut radiance = Vec3::ZERO;
    for depth in 0..s.max_depth {
        // Next-event estimation.
        let cand = Candidates::gather(lights, mode, s.k, x, n, rng);
        *overlapping += cand.m as u64;
        *queries += 1;
        if let Some((e, y)) = cand.sample(lights, mode, rng) {
            let em = &lights.emitters[e];
            let d = y - x;
            let l2 = d.length_squared();
            let w = d / l2.sqrt();
            let (cos_x, cos_y) = (n.dot(w), -em.normal.dot(w));
            let pdf_area = cand.pdf_area(lights, mode, e, l2);
            if cos_x > 0.0
                && cos_y > 0.0
                && pdf_area > 0.0
                && ng.dot(w) > 0.0
                && !world.occluded_between(x, ng, y, em.normal)
            {
                let pdf_light = pdf_area * l2 / cos_y;
                let proxy = cand.mis_pdf_area(lights, mode, e, x, n, y) * l2 / cos_y;
                let pdf_bsdf = cos_x * FRAC_1_PI;
                let f = albedo * FRAC_1_PI;
                radiance +=
                    throughput * f * em.radiance * (cos_x / pdf_light) * mis(proxy, pdf_bsdf);
            }
        }
        // BSDF sampling: the next vertex, and emission found there with MIS.
        let dir = cosine_hemisphere(n, Vec2::new(rng.next_f32(), rng.next_f32()));
        let cos_x = n.dot(dir);
        if cos_x <= 0.0 || ng.dot(dir) <= 0.0 {
            break;
        }
        let Some(hit) = world.trace(world.offset(x, ng, dir), dir) else {
            break;
        };
        throughput *= albedo;
        if hit.emission != Vec3::ZERO {
            let pdf_bsdf = cos_x * FRAC_1_PI;
            let e = lights
                .of_triangle
                .get(hit.triangle as usize)
                .copied()
                .unwrap_or(u32::MAX);
            let l2 = (hit.position - x).length_squared();
            let cos_y = hit.geo_normal.dot(-dir).abs();
            let proxy = if e == u32::MAX || cos_y <= 0.0 {
                0.0
            } else {
                cand.mis_pdf_area(lights, mode, e as usize, x, n, hit.position) * l2 / cos_y
            };
            radiance += throughput * hit.emission * mis(pdf_bsdf, proxy);
        }
        // Russian roulette after three bounces.
        if depth >= 2 {
            let survive = throughput.max_element().min(0.95);
            if rng.next_f32() >= survive {
                break;
            }
            throughput /= survive;
        }
        (x, n, ng, albedo) = (hit.position, hit.normal, hit.geo_normal, hit.albedo);
    }
    radiance
}

/// Renders `s.spp` passes; pass p uses frame seed hash(seed, p) for the light ranges.
fn render_pt(
    world: &World,
    g: &GBuffer,
    mode: LightSampling,
    s: &PtSettings,
    bound: ErrorBound,
    seed: u64,
    progress: &dyn Progress,
) -> PtOutput {
    let n_px = g.len();
    let mut sum = vec![Vec3::ZERO; n_px];
    let mut lights = Lights::new(world);
    let spp = s.spp.max(1);
    progress.begin("path tracing", u64::from(spp));
    let (mut overlapping, mut queries) = (0u64, 0u64);
    for pass in 0..spp {
        lights.set_frame(mode, bound, hash(&[seed, u64::from(pass)]) as u32);
        let lights = &lights;
        let (o, q) = sum
            .par_iter_mut()
            .enumerate()
            .map(|(i, acc)| {
                if !g.is_hit(i) || lights.emitters.is_empty() {
                    return (0, 0);
                }
                let mut rng = Rng::new(&[seed, i as u64, u64::from(pass), STREAM_PT]);
                let (mut o, mut q) = (0, 0);
                let l = trace_path(world, lights, mode, s, g, i, &mut rng, &mut o, &mut q);
                *acc += lgh_core::color::finite_or_zero(l);
                (o, q)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        overlapping += o;
        queries += q;
        progress.advance(1);
    }
    progress.end();
    let inv = 1.0 / spp as f32;
    PtOutput {
        radiance: sum.into_iter().map(|v| v * inv).collect(),
        avg_overlapping: overlapping as f64 / queries.max(1) as f64,
    }
}

/// Path tracing with stochastic light culling.
pub const PT_SLC: Method = Method::new(&Pt(LightSampling::Slc));
/// Path tracing with uniform light sampling.
pub const PT_UNIFORM: Method = Method::new(&Pt(LightSampling::Uniform));
/// Path tracing with clamped light ranges.
pub const PT_CLAMPED: Method = Method::new(&Pt(LightSampling::Clamped));

/// The `pt` methods, by their light selection.
struct Pt(LightSampling);

/// Statistics of a `pt` frame.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PtStats {
    /// Samples per pixel.
    pub spp: u32,
    /// Emissive triangles.
    pub emitters: usize,
    /// Mean number of lights whose influence sphere held a shading point.
    #[serde(rename = "avg_overlapping_lights")]
    pub avg_overlapping: f64,
    /// Error bound epsilon_max of the light ranges.
    pub error_bound: f32,
}

impl IndirectMethod for Pt {
    fn name(&self) -> &'static str {
        match self.0 {
            LightSampling::Slc => "pt-slc",
            LightSampling::Uniform => "pt-uniform",
            LightSampling::Clamped => "pt-clamped",
        }
    }

    fn about(&self) -> &'static str {
        match self.0 {
            LightSampling::Slc => {
                "Path tracing (all bounces, not VPLs) whose light sampling uses stochastic light culling: bounding sphere tree, reservoir sampling, resampled importance sampling"
            }
            LightSampling::Uniform => "Path tracing with uniform light sampling (baseline)",
            LightSampling::Clamped => "Path tracing with clamped light ranges (biased baseline)",
        }
    }

    fn illumination(&self) -> Illumination {
        Illumination::AllReflected
    }

    fn render(
        &self,
        inputs: &MethodInputs,
        _memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError> {
        let s = inputs.settings;
        let bound = s.error_bound_or(DEFAULT_ERROR_BOUND, inputs.world.scene.exposure);
        let out = render_pt(
            inputs.world,
            inputs.gbuffer,
            self.0,
            &s.pt,
            bound,
            s.seed,
            inputs.progress,
        );
        let stats = PtStats {
            spp: s.pt.spp,
            emitters: inputs.world.lights.emitters.len(),
            avg_overlapping: out.avg_overlapping,
            error_bound: bound.epsilon_max,
        };
        Ok(MethodOutput {
            radiance: out.radiance,
            stats: Some(Arc::new(stats)),
            ..MethodOutput::default()
        })
    }
}
