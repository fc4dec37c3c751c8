//! What the GPU tests share: the scenes they run on (each test file uses part of it).
#![allow(dead_code)]

use lgh_render::World;

/// The default scene (None) and the project's three test scenes.
pub const SCENES: [Option<&str>; 4] = [
    None,
    Some("test/two-rooms.toml"),
    Some("test/colonnade.toml"),
    Some("test/clutter.toml"),
];

pub fn world(rel: Option<&str>) -> World {
    let scene = match rel {
        None => {
            let mut s = lgh_scene::cornell::cornell_box();
            s.finish(std::path::Path::new("<built-in cornell>"))
                .expect("scene");
            s
        }
        Some(r) => {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../scenes")
                .join(r);
            lgh_scene::load(&p).expect("scene")
        }
    };
    World::new(scene)
}

/// A GPU method whose frames take the CPU's G-buffer and VPLs (it forwards everything but
/// `trace_gbuffer` and `generate_vpls`): its kernels alone, against the CPU's on the same
/// inputs. (The GPU's own VPLs equal the CPU's within 1e-4 but not bit for bit, and the
/// hierarchy built over them differs a little.)
pub struct OnCpuInputs(pub lgh_render::Method);

impl lgh_render::methods::IndirectMethod for OnCpuInputs {
    fn name(&self) -> &'static str {
        self.0.get().name()
    }
    fn about(&self) -> &'static str {
        self.0.get().about()
    }
    fn illumination(&self) -> lgh_render::methods::Illumination {
        self.0.get().illumination()
    }
    fn default_shadow_samples(&self) -> u32 {
        self.0.get().default_shadow_samples()
    }
    fn render(
        &self,
        inputs: &lgh_render::methods::MethodInputs,
        memory: &mut lgh_render::memory::FrameMemory,
    ) -> Result<lgh_render::methods::MethodOutput, lgh_render::settings::RenderError> {
        self.0.get().render(inputs, memory)
    }
    fn direct(
        &self,
        world: &World,
        g: &lgh_render::passes::gbuffer::GBuffer,
        s: &lgh_render::RenderSettings,
    ) -> Result<Option<lgh_render::direct::DirectOutput>, lgh_render::settings::RenderError> {
        self.0.get().direct(world, g, s)
    }
}
