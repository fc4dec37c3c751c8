//! Tests of lgh's GPU frame: VPLs and grids kept on the GPU against the frame of the same
//! VPLs read back.

use super::*;
use crate::grid::GpuGridBuilder;
use crate::lgh::testing::{FrameInputs, cornell, cornell_and_two_rooms};
use lgh_render::RenderSettings;

thread_local! {
    /// Makes this thread's GPU frames with grids kept on the GPU end in
    /// [`Attempt::Again`] once their hierarchies are built, as a step that cannot run
    /// on the GPU (lists past its binning, a table past its buffers) ends them.
    pub(super) static AGAIN: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// A frame whose VPLs stay on the GPU, never read back, is the frame of the same VPLs
/// read back, pixel for pixel: at the viewer's settings (S_1 lowest, and S_0 too; and
/// with one hierarchy per normal bin, the VPLs split on the GPU), and
/// where the frame has to be made with its grids on the CPU after all (one level shown
/// alone; a step that ends the frame on the GPU after its builds), from the kept
/// light-path records or, where those are gone, traced again.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn vpls_kept_on_the_gpu_give_the_frame_of_the_vpls_read_back() {
    let ctx = GpuContext::shared().expect("an adapter");
    let none = lgh_core::vpl::Vpls::default();
    let render = |inputs: &MethodInputs| {
        let mut memory = FrameMemory::default();
        let out = LGH_GPU.get().render(inputs, &mut memory).expect("frame");
        let stats = out.stats::<lgh_render::methods::lgh::LghStats>();
        (out.radiance.clone(), stats.expect("stats").grids_on_cpu)
    };
    for world in &cornell_and_two_rooms() {
        for (start_level, bins) in [(1, false), (0, false), (1, true)] {
            let mut s = RenderSettings {
                width: 48,
                height: 27,
                vpls: 3000,
                component: lgh_render::Component::Indirect,
                ..RenderSettings::default()
            };
            s.lgh.normal_bins = bins;
            s.lgh.start_level = start_level;
            s.lgh.alpha = 1.5;
            s.tiling.interleave = Some(4);
            s.shadows.samples = Some(4);
            let made = FrameInputs::new(world, &s);
            let read = |s: &RenderSettings| {
                let set = crate::vpls::method_vpls(world, s, (true, false))
                    .expect("gpu")
                    .expect("vpls");
                assert!(set.kept == 0 && !set.vpls.is_empty());
                let inputs = MethodInputs {
                    vpls: &set.vpls,
                    vpl_count: set.vpls.len(),
                    ..made.inputs(world, s)
                };
                (render(&inputs), set.vpls.len(), set.paths)
            };
            let kept = |s: &RenderSettings, records: bool| {
                let set = crate::vpls::method_vpls(world, s, (true, true))
                    .expect("gpu")
                    .expect("vpls");
                assert!(set.vpls.is_empty() && set.kept > 0);
                assert_eq!(set.kept_bins.is_some(), s.lgh.normal_bins);
                if !records {
                    crate::vpls::resident::clear(ctx);
                }
                let inputs = MethodInputs {
                    vpls: &none,
                    vpl_count: set.kept,
                    vpl_bins: set.kept_bins,
                    ..made.inputs(world, s)
                };
                (render(&inputs), set.kept, set.paths)
            };
            let (a, n, paths) = read(&s);
            let (b, kept_n, kept_paths) = kept(&s, true);
            assert_eq!((kept_n, kept_paths), (n, paths));
            assert!(a.0.iter().any(|p| p.max_element() > 0.0));
            assert!(
                a.0 == b.0,
                "start level {start_level}: kept VPLs, another image"
            );
            assert!(!b.1, "the grids stayed on the GPU");
            // Not read back: the light-path records are still kept.
            assert!(crate::vpls::resident::take_records(ctx, n).is_some());
            // Ended after its builds: made again with its grids and VPLs on the CPU.
            AGAIN.with(|a| a.set(true));
            let (again, _, _) = kept(&s, true);
            AGAIN.with(|a| a.set(false));
            assert!(
                a.0 == again.0,
                "start level {start_level}: made again, another image"
            );
            assert!(again.1, "made again with the grids on the CPU");
            // Made again with the grids on the CPU: the kept VPLs are read back.
            s.lgh.only_level = Some(2);
            let (a, _, _) = read(&s);
            for records in [true, false] {
                let (b, _, _) = kept(&s, records);
                assert!(a.0 == b.0, "one level, records {records}: another image");
                assert!(b.1, "grids on the CPU");
            }
        }
    }
}

/// A frame prepared from grids kept on the GPU holds no shaded light on the CPU where
/// every later step runs on the GPU (the unbiased estimate's shadow samples), and is
/// refused where a step needs them on the CPU (no shadow samples: the CPU packs the
/// lights; one level shown alone), which the GPU frame answers by building again with
/// the grids read back.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn grids_stay_on_the_gpu_only_for_frames_that_run_there() {
    let world = cornell();
    for (shadowed, only_level, resident) in [
        (true, None, true),
        (false, None, false),
        (true, Some(2), false),
    ] {
        let mut s = RenderSettings {
            width: 32,
            height: 18,
            vpls: 2000,
            ..RenderSettings::default()
        };
        s.lgh.only_level = only_level;
        let made = FrameInputs::new(&world, &s);
        let inputs = made.inputs(&world, &s);
        let ctx = GpuContext::shared().expect("an adapter");
        let mut builder = GpuGridBuilder::new(ctx);
        builder.keep_representatives(true);
        builder.keep_grid(true);
        let mut memory = FrameMemory::default();
        let prepared =
            LghFrame::prepare_with(&inputs, shadowed, &mut memory, true, Some(&mut builder));
        match prepared {
            Ok(Prepared::Frame(frame)) => {
                assert!(resident, "{shadowed} {only_level:?}: prepared");
                assert!(!frame.lights_on_cpu());
                let t = frame.tables(s.width, s.height).expect("tables");
                assert!(t.lights.is_empty() && t.light_count > 1000);
                assert!(t.hierarchies.iter().all(|h| h.grid.lookups_on_device));
            }
            Err(e) => {
                assert!(!resident, "{shadowed} {only_level:?}: {e}");
                assert_eq!(e, GridError::KeptOnDevice);
            }
            Ok(Prepared::Dark(_)) => panic!("a dark frame"),
        }
    }
}
