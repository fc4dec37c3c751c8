//! What the unbiased estimate's shadow targets read of every hierarchy, joined into one buffer
//! each for the lighting loop: the S_1 lights' representatives (VPL indices) and the VPLs
//! they index. Where the GPU built a hierarchy it holds both already, as the build left them
//! ([`crate::grid::Held`]): they are bound as they are (one hierarchy) or copied together on
//! the GPU (six), and neither is read back nor uploaded. Where the CPU built one, its part is
//! packed from the frame's tables ([`GridTables`]) and uploaded.

use lgh_core::lighting_grid::representative::SLOTS;
use lgh_render::methods::lgh::tables::{GridTables, LghTables};
use rayon::prelude::*;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::grid::{Held, LIGHT_BYTES};
use crate::pool::Lease;

/// One hierarchy's part of a joined buffer: where the GPU holds it, or its words from the
/// CPU.
enum Part<'c> {
    OnGpu(Lease<'c>),
    FromCpu(Vec<u32>),
}

/// The loop's buffers of the representatives (`SLOTS` words per S_1 light, hierarchy after
/// hierarchy) and of the VPLs they index ([`LIGHT_BYTES`] a VPL: position, flux, normal, the
/// build's layout), from what the GPU holds of each hierarchy (`held`, in hierarchy order)
/// or from the tables `t`. The copies are recorded in `batch`, which keeps what they read and
/// the builds' records and their numbers (which the lookups read, [`super::lookups`]).
///
/// # Errors
/// `held` does not match the hierarchies, a hierarchy's part is neither held nor in the
/// tables, or a buffer cannot be had.
pub(super) fn join<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    t: &LghTables,
    held: Vec<Option<Held<'c>>>,
) -> Result<(Lease<'c>, Lease<'c>), GpuError> {
    if t.hierarchies.is_empty() {
        // Nothing reads them (no shadow samples); a binding needs a buffer.
        return Ok((
            ctx.output("representatives", 4 * SLOTS as u64)?,
            ctx.output("representatives' VPLs", LIGHT_BYTES)?,
        ));
    }
    if held.len() != t.hierarchies.len() {
        return Err(GpuError::Failed(format!(
            "lgh on the GPU: {} hierarchies but {} builds",
            t.hierarchies.len(),
            held.len()
        )));
    }
    let missing = |what: &str| {
        GpuError::Failed(format!(
            "lgh on the GPU: a hierarchy's {what} are neither on the GPU nor in its tables"
        ))
    };
    let (mut slots, mut vpls) = (Vec::new(), Vec::new());
    for (h, held) in t.hierarchies.iter().zip(held) {
        let g: &GridTables = h.grid;
        let (on_gpu_vpls, on_gpu_slots) = match held {
            Some(Held {
                lights,
                slots,
                records,
                numbered,
                ..
            }) => {
                // The lookups read the records and their numbers in this batch
                // ([`super::lookups`]): a lease dropped before its batch ran may be leased
                // by another frame.
                if let Some(records) = records {
                    batch.keep(records);
                }
                if let Some(n) = numbered {
                    batch.keep(n.index);
                    batch.keep(n.total);
                }
                (Some(lights), slots)
            }
            None => (None, None),
        };
        let slot_bytes = 4 * (SLOTS * g.s1_count) as u64;
        slots.push((
            match on_gpu_slots {
                Some(lease) if lease.bytes() >= slot_bytes => Part::OnGpu(lease),
                _ if g.rep_vpls.len() == g.s1_count => {
                    Part::FromCpu(g.rep_vpls.iter().flatten().copied().collect())
                }
                _ => return Err(missing("representatives")),
            },
            slot_bytes,
        ));
        let vpl_bytes = LIGHT_BYTES * g.vpl_count as u64;
        vpls.push((
            match on_gpu_vpls {
                Some(lease) if lease.bytes() >= vpl_bytes => Part::OnGpu(lease),
                _ if g.vpls.len() == g.vpl_count => Part::FromCpu(
                    g.vpls
                        .par_iter()
                        .flat_map_iter(|v| {
                            [v.position, v.colour, v.normal]
                                .into_iter()
                                .flat_map(|c| c.to_array().map(f32::to_bits))
                        })
                        .collect(),
                ),
                _ => return Err(missing("VPLs")),
            },
            vpl_bytes,
        ));
    }
    Ok((
        joined(ctx, batch, "representatives", slots)?,
        joined(ctx, batch, "representatives' VPLs", vpls)?,
    ))
}

/// The parts (each with its bytes) one after the other in one buffer: a single part as it
/// is, several copied together on the GPU.
fn joined<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    label: &'static str,
    parts: Vec<(Part<'c>, u64)>,
) -> Result<Lease<'c>, GpuError> {
    let mut leases = Vec::with_capacity(parts.len());
    for (part, bytes) in parts {
        let lease = match part {
            Part::OnGpu(lease) => lease,
            Part::FromCpu(words) if words.is_empty() => ctx.output(label, 4)?,
            Part::FromCpu(words) => ctx.upload(label, &words)?,
        };
        leases.push((lease, bytes));
    }
    if leases.len() == 1 {
        return leases
            .pop()
            .map(|(lease, _)| lease)
            .ok_or_else(|| GpuError::Failed("no part".into()));
    }
    let total: u64 = leases.iter().map(|(_, bytes)| bytes).sum();
    let all = ctx.output(label, total.max(4))?;
    let mut at = 0u64;
    for (lease, bytes) in leases {
        if bytes > 0 {
            batch.copy(&lease, 0, &all, at, bytes);
        }
        at += bytes;
        batch.keep(lease);
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{GpuGridBuilder, LIGHT_FLOATS};
    use crate::lgh::testing::{FrameInputs, cornell, prepare};
    use glam::Vec3;
    use lgh_core::color::luminance;
    use lgh_core::lighting_grid::HierarchyBuilder;
    use lgh_render::RenderSettings;

    /// The joined representatives and their VPLs of the default scene's frame (one
    /// hierarchy, or six by normal), read back: from what the GPU builds held (`keep`:
    /// the representatives too) or packed from the tables of hierarchies the CPU built.
    fn read_joined(normal_bins: bool, on_gpu: bool, keep: bool) -> (Vec<u32>, Vec<f32>) {
        let world = cornell();
        let mut s = RenderSettings {
            width: 32,
            height: 18,
            vpls: 3000,
            ..RenderSettings::default()
        };
        s.lgh.normal_bins = normal_bins;
        let made = FrameInputs::new(&world, &s);
        let ctx = GpuContext::shared().expect("an adapter");
        let mut builder = GpuGridBuilder::new(ctx);
        builder.keep_representatives(keep);
        let b: Option<&mut dyn HierarchyBuilder> = on_gpu.then_some(&mut builder as _);
        let frame = prepare(&made.inputs(&world, &s), b);
        let held = builder.take_held();
        let tables = frame.tables(s.width, s.height).expect("tables");
        let hierarchies = tables.hierarchies.len();
        assert_eq!(hierarchies, if normal_bins { 6 } else { 1 });
        assert_eq!(held.len(), if on_gpu { hierarchies } else { 0 });
        let kept_slots = held.iter().flatten().filter(|h| h.slots.is_some()).count();
        assert_eq!(kept_slots, if on_gpu && keep { hierarchies } else { 0 });
        let held = if on_gpu {
            held
        } else {
            (0..hierarchies).map(|_| None).collect()
        };
        let mut batch = Batch::new(ctx);
        let (slots, reps) = join(ctx, &mut batch, &tables, held).expect("joined");
        let s1: usize = tables.hierarchies.iter().map(|h| h.grid.s1_count).sum();
        let total: usize = tables.hierarchies.iter().map(|h| h.grid.vpl_count).sum();
        assert_eq!(total, made.vpl_count());
        batch
            .read(slots.buffer(), 4 * (SLOTS * s1) as u64)
            .expect("read");
        batch
            .read(reps.buffer(), LIGHT_BYTES * total as u64)
            .expect("read");
        let (reads, _) = batch.finish().expect("gpu");
        (
            bytemuck::cast_slice::<_, u32>(&reads[0]).to_vec(),
            bytemuck::cast_slice::<_, f32>(&reads[1])[..LIGHT_FLOATS * total].to_vec(),
        )
    }

    /// What a GPU-built frame's loop reads where its builds held it on the GPU (no read-back,
    /// no upload) is what the CPU packs from the tables: the same representatives, and VPLs
    /// with the same positions and normals bit for bit and the same flux colour (the loop
    /// reads the flux at unit luminance), with one hierarchy (bound as the build held it)
    /// and with six (copied into one buffer). The representatives are compared with the
    /// same GPU draw read back and packed by the CPU (a CPU-built hierarchy is a slightly
    /// different grid, whose draw may differ; tests/grid.rs checks the GPU's draw against
    /// the CPU's on the same grid).
    #[test]
    #[cfg_attr(
        not(gpu_adapter),
        ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
    )]
    fn what_the_builds_hold_is_what_the_cpu_packs() {
        let vec = |r: &[f32], i: usize, at: usize| {
            Vec3::from_slice(&r[LIGHT_FLOATS * i + at..LIGHT_FLOATS * i + at + 3])
        };
        let chroma = |c: Vec3| c / luminance(c);
        for normal_bins in [false, true] {
            let (cpu_slots, cpu) = read_joined(normal_bins, false, false);
            let (read_slots, _) = read_joined(normal_bins, true, false);
            let (gpu_slots, gpu) = read_joined(normal_bins, true, true);
            assert!(!gpu_slots.is_empty());
            assert_eq!(gpu_slots, read_slots, "representatives kept / read back");
            // (The CPU-built hierarchies' representatives are another grid's draw.)
            assert!(!cpu_slots.is_empty());
            assert_eq!(gpu.len(), cpu.len());
            for i in 0..gpu.len() / LIGHT_FLOATS {
                assert_eq!(vec(&gpu, i, 0), vec(&cpu, i, 0), "position {i}");
                assert_eq!(vec(&gpu, i, 6), vec(&cpu, i, 6), "normal {i}");
                let (a, b) = (chroma(vec(&gpu, i, 3)), chroma(vec(&cpu, i, 3)));
                assert!((a - b).abs().max_element() < 1e-5, "colour {i}: {a} {b}");
            }
        }
    }
}
