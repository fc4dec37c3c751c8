//! lgh's shaded lights made on the GPU from what the hierarchy builds hold
//! (`shaders/lights/`): the loop's light table and the tile binning's spheres, the same
//! values in the same order as the CPU's (`LghFrame`'s shaded lights as
//! [`super::upload::Tables`] and the binning's packing make them; LGH 2019 section 3.2),
//! so that neither is packed on the CPU nor uploaded (64 + 20 bytes a shaded light).
//!
//! Per hierarchy: where the VPLs are shaded as S_0, one invocation per VPL writes its row
//! from the build's input lights; the grid lights come from the build's records, whose
//! zero-intensity ones the CPU drops as it unpacks the grid: a flag per record, a
//! [`scan`](crate::scan) of the flags (each kept record's grid index), and one invocation per
//! record writes its row. The level of a record, and so its radius, role and sub-image,
//! follow from where the levels' records start.

use lgh_core::blending::LevelRole;
use lgh_core::lighting_grid::MAX_LEVELS;
use lgh_core::vpl::GridEmission;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::tables::LghTables;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::grid::Held;
use crate::pool::Lease;

/// Per-level entries of [`LightParams`] (levels 0..=[`MAX_LEVELS`], and room).
const LEVELS: usize = 12;
const _: () = assert!(MAX_LEVELS as usize + 2 <= LEVELS);

/// `Level` of `shaders/lights/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Level {
    radius: f32,
    reach: f32,
    rise: f32,
    fall: f32,
}

/// `LightParams` of `shaders/lights/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LightParams {
    count: u32,
    base: u32,
    n2: u32,
    normals: u32,
    scale: f32,
    energy: u32,
    l_max: u32,
    _p: u32,
    level: [Level; LEVELS],
    start: [[u32; 4]; LEVELS],
}

/// The WGSL sources of the two kernels: grid rows, VPL rows.
#[must_use]
pub fn sources() -> [String; 2] {
    let common = include_str!("../shaders/lights/common.wgsl");
    let write = include_str!("../shaders/lights/write.wgsl");
    [
        crate::kernel(&[common, write, include_str!("../shaders/lights/rows.wgsl")]),
        crate::kernel(&[
            common,
            write,
            include_str!("../shaders/lights/vpl_rows.wgsl"),
        ]),
    ]
}

/// The shaded lights as the GPU made them.
pub(super) struct GpuLights<'c> {
    /// The loop's light table (four vec4 a light).
    pub table: Lease<'c>,
    /// The binning's spheres (centre, finite radius; the emission normal it culls by) and
    /// sub-images with flags.
    pub spheres: Lease<'c>,
    pub flags: Lease<'c>,
}

/// Records into `batch` the making of the `lights` shaded lights of the frame (`inputs`,
/// loop inputs `t`) from what its builds hold (`held`, in hierarchy order); `None` (the CPU
/// packs them) where a hierarchy was built on the CPU or did not keep its records, or the
/// frame shows one level alone.
///
/// # Errors
/// A buffer cannot be had, or a dispatch or scan is too large.
pub(super) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    inputs: &MethodInputs,
    t: &LghTables,
    held: &[Option<Held<'c>>],
    lights: usize,
) -> Result<Option<GpuLights<'c>>, GpuError> {
    let settings = &inputs.settings.lgh;
    let holds_all = held.len() == t.hierarchies.len()
        && held
            .iter()
            .all(|h| h.as_ref().is_some_and(|h| h.records.is_some()));
    if t.hierarchies.is_empty() || !holds_all || settings.only_level.is_some() || lights == 0 {
        return Ok(None);
    }
    let n2 = t.n.max(1) * t.n.max(1);
    let out = GpuLights {
        table: ctx.output("lights", 64 * lights as u64)?,
        spheres: ctx.output("bin spheres", 32 * lights as u64)?,
        flags: ctx.output("bin flags", 4 * lights as u64)?,
    };
    let [rows_src, vpl_src] = sources();
    for (h, held) in t.hierarchies.iter().zip(held.iter().flatten()) {
        let Some(records) = &held.records else {
            continue;
        };
        let grid = h.grid;
        let (lowest, l_max) = (grid.levels.lowest, grid.geometry.l_max);
        let mut level = [Level::default(); LEVELS];
        for (l, lv) in level.iter_mut().enumerate().take(l_max as usize + 1) {
            let radius = grid.geometry.radius(l as u32, grid.levels.alpha);
            let role = LevelRole::of(l as u32, lowest, l_max);
            let reach = role.reach(radius);
            let (rise, fall) = role.floors();
            *lv = Level {
                radius,
                reach: if reach.is_finite() { reach } else { -1.0 },
                rise,
                fall,
            };
        }
        let mut start = [[0u32; 4]; LEVELS];
        let mut at = 0u32;
        for (l, &c) in held.level_records.iter().enumerate().take(LEVELS - 2) {
            start[l + 1][0] = at;
            at += c;
        }
        start[(l_max as usize + 1).min(LEVELS - 1)][0] = at;
        let base = LightParams {
            count: at,
            base: h.grid_base,
            n2,
            // lgh's VPLs always carry normals (`Vpls::as_input`), and so do the records.
            normals: 1,
            scale: n2 as f32,
            energy: u32::from(settings.emission == GridEmission::EnergyConserving),
            l_max,
            _p: 0,
            level,
            start,
        };
        if lowest == 0 {
            let params = LightParams {
                count: grid.vpl_count as u32,
                base: h.first,
                ..base
            };
            let uniform = batch.uniform(&params)?;
            let pipeline = ctx.pipeline("lights vpl rows", || vpl_src.clone());
            let bind = ctx.bind_group(
                &pipeline,
                vec![
                    uniform.as_entire_binding(),
                    held.lights.binding(),
                    out.table.binding(),
                    out.spheres.binding(),
                    out.flags.binding(),
                ],
            );
            batch.dispatch("light_table", &pipeline, &bind, params.count as usize)?;
        }
        let (true, Some(numbers)) = (at > 0, &held.numbered) else {
            continue;
        };
        let uniform = batch.uniform(&base)?;
        let pipeline = ctx.pipeline("lights rows", || rows_src.clone());
        let bind = ctx.bind_group(
            &pipeline,
            vec![
                uniform.as_entire_binding(),
                records.binding(),
                numbers.index.binding(),
                out.table.binding(),
                out.spheres.binding(),
                out.flags.binding(),
            ],
        );
        batch.dispatch("light_table", &pipeline, &bind, at as usize)?;
    }
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GpuGridBuilder;
    use crate::lgh::testing::{FrameInputs, cornell_and_two_rooms, prepare};
    use glam::Vec4;
    use lgh_render::{RenderSettings, World};

    /// The shaded lights of `world`'s frame of `s`, as the GPU makes them (table, spheres,
    /// flags) and as the CPU packs them.
    #[allow(clippy::type_complexity)]
    fn both(
        world: &World,
        s: &RenderSettings,
    ) -> (
        (Vec<[Vec4; 4]>, Vec<Vec4>, Vec<u32>),
        (Vec<[Vec4; 4]>, Vec<Vec4>, Vec<u32>),
    ) {
        let made = FrameInputs::new(world, s);
        let inputs = made.inputs(world, s);
        let ctx = GpuContext::shared().expect("an adapter");
        let mut builder = GpuGridBuilder::new(ctx);
        builder.keep_representatives(true);
        let frame = prepare(&inputs, Some(&mut builder));
        let held = builder.take_held();
        let t = frame.tables(s.width, s.height).expect("tables");
        let cpu_table = super::super::upload::Tables::new(&t, true)
            .expect("tables")
            .lights;
        let (cpu_spheres, cpu_flags) = crate::bins::pack_spheres(&frame.spheres());
        let mut batch = Batch::new(ctx);
        let made = record(ctx, &mut batch, &inputs, &t, &held, t.light_count)
            .expect("record")
            .expect("made on the GPU");
        batch
            .read(made.table.buffer(), made.table.bytes())
            .expect("read");
        batch
            .read(made.spheres.buffer(), made.spheres.bytes())
            .expect("read");
        batch
            .read(made.flags.buffer(), made.flags.bytes())
            .expect("read");
        let (reads, _) = batch.finish().expect("gpu");
        let n = t.lights.len();
        let table: &[[Vec4; 4]] = bytemuck::cast_slice(&reads[0]);
        let spheres: &[Vec4] = bytemuck::cast_slice(&reads[1]);
        let flags: &[u32] = bytemuck::cast_slice(&reads[2]);
        (
            (
                table[..n].to_vec(),
                spheres[..2 * n].to_vec(),
                flags[..n].to_vec(),
            ),
            (cpu_table, cpu_spheres, cpu_flags),
        )
    }

    /// The GPU makes the CPU's shaded lights from what the builds hold: every row of the
    /// loop's table bit for bit but for the isotropic share (a length, 1e-6), and the tile
    /// binning's spheres and flags, on the default scene and two-rooms, at the render's
    /// defaults (six hierarchies, the VPLs as S_0, 2 x 2 interleaving) and the viewer's
    /// (one hierarchy from S_1, 4 x 4, alpha 1.5, the demo's emission).
    #[test]
    #[cfg_attr(
        not(gpu_adapter),
        ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
    )]
    fn the_gpu_makes_the_cpus_shaded_lights() {
        for world in &cornell_and_two_rooms() {
            for viewer in [false, true] {
                let mut s = RenderSettings {
                    width: 48,
                    height: 27,
                    vpls: 3000,
                    ..RenderSettings::default()
                };
                if viewer {
                    s.lgh.start_level = 1;
                    s.lgh.normal_bins = false;
                    s.lgh.alpha = 1.5;
                    s.lgh.emission = GridEmission::MeanNormal;
                    s.tiling.interleave = Some(4);
                }
                let ((table, spheres, flags), (cpu_table, cpu_spheres, cpu_flags)) =
                    both(world, &s);
                assert_eq!(table.len(), cpu_table.len());
                assert!(table.len() > 300, "{} lights", table.len());
                for (j, (a, b)) in table.iter().zip(&cpu_table).enumerate() {
                    assert_eq!(a[0], b[0], "light {j}: position, reach^2");
                    assert_eq!(a[1].truncate(), b[1].truncate(), "light {j}: normal");
                    assert!((a[1].w - b[1].w).abs() <= 1e-6, "light {j}: iso");
                    assert_eq!(a[2], b[2], "light {j}: intensity, radius");
                    assert_eq!(a[3], b[3], "light {j}: floors, level, vertex");
                }
                assert_eq!(spheres, cpu_spheres);
                assert_eq!(flags, cpu_flags);
            }
        }
    }
}
