//! What the unit tests of a GPU lgh frame's steps share: the default scene, and a frame's
//! inputs made on the CPU and prepared with the loop's tables.

use lgh_core::lighting_grid::HierarchyBuilder;
use lgh_render::memory::FrameMemory;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::{LghFrame, Prepared};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::passes::vpl_gen::{VplSet, generate_vpls};
use lgh_render::{RenderSettings, Silent, World};
use lgh_scene::camera::CameraFrame;

/// The built-in Cornell box.
pub(super) fn cornell() -> World {
    let mut scene = lgh_scene::cornell::cornell_box();
    scene
        .finish(std::path::Path::new("<built-in cornell>"))
        .expect("scene");
    World::new(scene)
}

/// The built-in Cornell box and the two-rooms test scene (light through a door).
pub(super) fn cornell_and_two_rooms() -> [World; 2] {
    let two_rooms =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/test/two-rooms.toml");
    [
        cornell(),
        World::new(lgh_scene::load(&two_rooms).expect("scene")),
    ]
}

/// A frame's camera, G-buffer and VPLs, made on the CPU.
pub(super) struct FrameInputs {
    camera: CameraFrame,
    g: GBuffer,
    vpls: VplSet,
}

impl FrameInputs {
    /// The inputs of `world`'s frame of `s`.
    pub(super) fn new(world: &World, s: &RenderSettings) -> Self {
        let camera = world.scene.camera().frame(s.width, s.height);
        let g = GBuffer::render(world, &camera, s.width, s.height);
        let vpls = generate_vpls(world, s.vpls, s.bounces, s.seed, s.path_numbers);
        Self { camera, g, vpls }
    }

    /// The number of VPLs.
    pub(super) fn vpl_count(&self) -> usize {
        self.vpls.vpls.len()
    }

    /// As a method reads them.
    pub(super) fn inputs<'a>(
        &'a self,
        world: &'a World,
        s: &'a RenderSettings,
    ) -> MethodInputs<'a> {
        MethodInputs {
            world,
            gbuffer: &self.g,
            camera: &self.camera,
            vpls: &self.vpls.vpls,
            vpl_count: self.vpls.vpls.len(),
            vpl_bins: None,
            settings: s,
            progress: &Silent,
        }
    }
}

/// The frame of `inputs` prepared with the loop's tables, its hierarchies built by
/// `builder` (the CPU's where `None`).
pub(super) fn prepare(
    inputs: &MethodInputs,
    builder: Option<&mut dyn HierarchyBuilder>,
) -> Box<LghFrame> {
    let mut memory = FrameMemory::default();
    let Ok(Prepared::Frame(frame)) =
        LghFrame::prepare_with(inputs, true, &mut memory, true, builder)
    else {
        panic!("a frame with VPLs");
    };
    frame
}
