//! The brute-force reference on the GPU (`shaders/brute.wgsl`): every pixel sums every VPL,
//! with an exact shadow ray per VPL traced through the BVH in compute, as lgh-render's
//! `brute` does on the CPU (the same formula, offsets and clamp; docs/design.md, "Clamps").
//! It checks the GPU's rays and shading against the CPU's.
//!
//! VPLs go to the GPU in chunks, one dispatch each, so that no single dispatch runs long
//! enough for a desktop driver's watchdog; each pixel adds its chunk sums in chunk order, so
//! the image is the same from run to run.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec3, Vec4};
use lgh_render::memory::FrameMemory;
use lgh_render::methods::{IndirectMethod, Method, MethodInputs, MethodOutput};
use lgh_render::settings::RenderError;

use bytemuck::Zeroable;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};

/// Every pixel sums every VPL with an exact shadow ray, on the GPU.
pub const BRUTE_GPU: Method = Method::new(&GpuBrute { shadowed: true });
/// Every pixel sums every VPL without shadow rays, on the GPU.
pub const BRUTE_UNSHADOWED_GPU: Method = Method::new(&GpuBrute { shadowed: false });

/// Pixel-VPL pairs per dispatch at most (about 0.1 s of work on a current GPU).
const PAIRS_PER_DISPATCH: usize = 1 << 28;

/// VPLs per dispatch at most. On lavapipe (Mesa 22.3) an invocation that traced more than
/// about 1,000 shadow rays in one dispatch lost part of its sum (the image came out up to
/// 26% dark), while the same work in dispatches of up to 1,000 VPLs was exact; the cause is
/// not found (docs/design.md, "GPU").
const MAX_VPLS_PER_DISPATCH: usize = 256;

struct GpuBrute {
    shadowed: bool,
}

impl GpuBrute {
    /// The brute force reads its VPLs from the CPU's copy and builds no hierarchy.
    #[allow(clippy::unused_self)]
    fn vpl_places(&self, _: &lgh_render::RenderSettings) -> (bool, bool) {
        (false, false)
    }
}

/// `Params` of the shader.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    pixels: u32,
    first_vpl: u32,
    vpl_count: u32,
    shadows: u32,
    eps2: f32,
    ray_eps: f32,
    _pad: [u32; 2],
}

impl IndirectMethod for GpuBrute {
    fn name(&self) -> &'static str {
        if self.shadowed {
            "brute"
        } else {
            "brute-unshadowed"
        }
    }

    fn about(&self) -> &'static str {
        "Every pixel sums every VPL (with an exact shadow ray each unless unshadowed), on the GPU"
    }

    crate::gpu_frame_passes!(vpls: vpl_places);

    fn render(&self, i: &MethodInputs, _: &mut FrameMemory) -> Result<MethodOutput, RenderError> {
        let fail = |e: GpuError| RenderError::Backend(e.to_string());
        let ctx = GpuContext::shared().map_err(fail)?;
        let irradiance = render_brute(ctx, i, self.shadowed).map_err(fail)?;
        let g = i.gbuffer;
        let radiance = irradiance
            .iter()
            .zip(&g.albedo)
            .enumerate()
            .map(|(p, (e, a))| {
                if g.is_hit(p) {
                    *a * FRAC_1_PI * e.truncate()
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        Ok(MethodOutput {
            radiance,
            ..MethodOutput::default()
        })
    }
}

/// The WGSL source of the kernel (with the BVH traversal).
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/brute.wgsl"),
        include_str!("../shaders/bvh.wgsl"),
    ])
}

/// Irradiance sums E (the sum of every VPL's unshadowed or shadowed irradiance) per pixel.
fn render_brute(ctx: &GpuContext, i: &MethodInputs, shadows: bool) -> Result<Vec<Vec4>, GpuError> {
    let (g, vpls) = (i.gbuffer, i.vpls);
    let n = g.len();
    let scene = ctx.scene(i.world)?;
    let vpl_data: Vec<[Vec4; 3]> = (0..vpls.len())
        .map(|j| {
            [
                vpls.positions[j].extend(1.0),
                vpls.normals[j].extend(0.0),
                vpls.flux[j].extend(0.0),
            ]
        })
        .collect();
    if vpls.is_empty() {
        return Ok(vec![Vec4::ZERO; n]);
    }
    let gbuffer = ctx.gbuffer(g)?;
    let vpl_buf = ctx.upload("vpls", &vpl_data)?;
    let out = ctx.output("irradiance", 16 * n as u64)?;
    let params = ctx.uniform("brute params", &Params::zeroed());
    let pipeline = ctx.pipeline("brute", source);
    let mut resources = scene.bindings(params.as_entire_binding(), &gbuffer);
    resources.extend([vpl_buf.binding(), out.binding()]);
    let bind = ctx.bind_group(&pipeline, resources);
    let chunk = (PAIRS_PER_DISPATCH / n.max(1)).clamp(1, MAX_VPLS_PER_DISPATCH);
    let eps = i.eps();
    i.progress.begin(
        "indirect (brute force, GPU)",
        vpls.len().div_ceil(chunk) as u64,
    );
    let mut irradiance = Vec::new();
    for first in (0..vpls.len()).step_by(chunk) {
        let p = Params {
            pixels: n as u32,
            first_vpl: first as u32,
            vpl_count: chunk.min(vpls.len() - first) as u32,
            shadows: u32::from(shadows),
            eps2: eps * eps,
            ray_eps: i.world.ray_epsilon,
            _pad: [0; 2],
        };
        // One submission per chunk: the parameters are written between them.
        ctx.queue.write_buffer(&params, 0, bytemuck::bytes_of(&p));
        let mut batch = Batch::new(ctx);
        if first == 0 {
            batch.clear(out.buffer());
        }
        batch.dispatch("brute", &pipeline, &bind, n)?;
        let last = first + chunk >= vpls.len();
        if last {
            batch.read(out.buffer(), out.bytes())?;
        }
        let (reads, _) = batch.finish()?;
        if last && let Some(r) = reads.first() {
            irradiance = bytemuck::cast_slice::<_, Vec4>(r)[..n].to_vec();
        }
        i.progress.advance(1);
    }
    i.progress.end();
    Ok(irradiance)
}
