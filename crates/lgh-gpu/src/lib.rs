//! The GPU backend of lgh: the frame's passes as wgpu compute shaders (WGSL), on any adapter
//! wgpu finds (Vulkan, Metal, DX12; Mesa's lavapipe on a machine without a GPU).
//!
//! What runs here (issue 35): a [`GpuContext`] (adapter, device, queue, buffers leased
//! between frames, the frame's G-buffer kept while it stands still) and [`Batch`] (a frame's
//! passes in one submission, timed); the scene uploaded with a BVH built on the CPU
//! ([`GpuScene`]: obvhs's binary BVH, flattened, traversed in compute: no ray-tracing
//! hardware is needed); the brute-force reference ([`brute::BRUTE_GPU`],
//! [`brute::BRUTE_UNSHADOWED_GPU`]), which checks the GPU's rays and shading against the
//! CPU's; `lgh` with its lighting loop, shadow-sample selection, unbiased shadow targets and
//! shadow rays ([`lgh::LGH_GPU`]) followed by the interleaving blur ([`interleave`], with the
//! filling of cut recombination windows, [`fill`]) and the ratio estimator ([`ratio`],
//! [`atrous`]); the direct light of both ([`direct`]); and the
//! lighting grid hierarchy with its S_1 lights' representatives ([`grid`], built with an
//! integer prefix sum, [`scan`]). The frame's passes before shading run here too: primary
//! rays into the G-buffer ([`primary`], with the scene's [`surfaces`]), VPL generation by
//! light tracing with the CPU's Sobol numbers ([`vpls`]), and the edge resolve's sub-pixel
//! samples ([`edges`]), and the tile binning of lgh's shaded lights ([`bins`]). The
//! unbiased estimate's other tables and the composite run on the CPU.
//!
//! The GPU methods are [`lgh_render::Method`]s like the CPU's: `render_frame` runs them with
//! the same settings and gives the same `Frame`. Results are deterministic: every pixel sums
//! its own terms in a fixed order (no float atomics).

pub mod batch;
mod context;
mod cutouts;
pub mod gbuffer;
pub mod grid;
pub mod interleave;
pub mod pool;
pub mod scene;
pub mod surfaces;
pub mod vpls;

pub mod atrous;
pub mod bins;
pub mod brute;
pub mod direct;
pub mod display;
pub mod edges;
pub mod fill;
pub mod lgh;
pub mod primary;
pub mod ratio;
pub mod rays;
pub mod scan;

pub use batch::Batch;
pub use context::{GpuContext, GpuError};
pub use pool::Lease;
pub use scene::GpuScene;

/// The hooks of lgh-render's `IndirectMethod` by which a GPU method runs the frame's other
/// passes on the GPU: the G-buffer ([`primary`]), the VPLs ([`vpls`]; the method's
/// `$vpls(&self, settings) -> (bool, bool)` says whether they are also kept on the GPU
/// for its hierarchy build, and whether they are kept there only, not read back), the
/// direct light ([`direct`]) and the edge resolve ([`edges`]). Expanded inside the
/// method's `impl IndirectMethod`.
macro_rules! gpu_frame_passes {
    (vpls: $vpls:ident) => {
        fn direct(
            &self,
            world: &lgh_render::World,
            g: &lgh_render::passes::gbuffer::GBuffer,
            s: &lgh_render::RenderSettings,
        ) -> Result<Option<lgh_render::direct::DirectOutput>, lgh_render::settings::RenderError> {
            crate::direct::method_direct(world, g, s)
        }

        fn trace_gbuffer(
            &self,
            world: &lgh_render::World,
            camera: &lgh_scene::camera::CameraFrame,
            size: (u32, u32),
            g: &mut lgh_render::passes::gbuffer::GBuffer,
            keep_on_device: bool,
        ) -> Result<bool, lgh_render::settings::RenderError> {
            crate::primary::method_gbuffer(world, camera, size, g, keep_on_device)
        }

        fn generate_vpls(
            &self,
            world: &lgh_render::World,
            s: &lgh_render::RenderSettings,
        ) -> Result<Option<lgh_render::passes::vpl_gen::VplSet>, lgh_render::settings::RenderError>
        {
            crate::vpls::method_vpls(world, s, self.$vpls(s))
        }

        fn edge_resolve(
            &self,
            world: &lgh_render::World,
            camera: &lgh_scene::camera::CameraFrame,
            g: &lgh_render::passes::gbuffer::GBuffer,
            samples: u32,
        ) -> Result<
            Option<lgh_render::passes::edge_aa::EdgeResolve>,
            lgh_render::settings::RenderError,
        > {
            crate::edges::method_edge_resolve(world, camera, g, samples)
        }
    };
}
pub(crate) use gpu_frame_passes;

/// A kernel's WGSL: the shared declarations (`shaders/common.wgsl`: the G-buffer's `Pixel`, `Vpl`,
/// `luminance`, `hash`, `PI`) followed by `parts` (the kernel, and `shaders/bvh.wgsl` for the
/// kernels that trace rays).
pub(crate) fn kernel(parts: &[&str]) -> String {
    let mut source = include_str!("shaders/common.wgsl").to_owned();
    for part in parts {
        source.push_str(part);
    }
    source
}

/// The GPU method for a frame of `settings`: [`gpu_method`] of its method, or `None` where
/// that method's GPU version does not run these settings (lgh with a shadow estimate other
/// than the default, [`lgh::supported`]), so that a caller that falls back to the CPU (the
/// viewer, whose keys change the estimate) renders that frame there.
#[must_use]
pub fn gpu_method_for(settings: &lgh_render::RenderSettings) -> Option<lgh_render::Method> {
    let m = gpu_method(settings.method)?;
    let lgh = m == lgh::LGH_GPU && settings.shadow_samples() > 0;
    (!lgh || lgh::supported(&settings.lgh).is_ok()).then_some(m)
}

/// The GPU method standing for the CPU method `method`, if it has been ported.
#[must_use]
pub fn gpu_method(method: lgh_render::Method) -> Option<lgh_render::Method> {
    match method.name() {
        "brute" => Some(brute::BRUTE_GPU),
        "brute-unshadowed" => Some(brute::BRUTE_UNSHADOWED_GPU),
        "lgh" => Some(lgh::LGH_GPU),
        "lgh-unshadowed" => Some(lgh::LGH_UNSHADOWED_GPU),
        _ => None,
    }
}
