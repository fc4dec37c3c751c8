//! The lighting loop's inputs ([`LghTables`]) packed as the buffers and uniform of
//! `shaders/lgh.wgsl`.

use glam::Vec4;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::settings::Selection;
use lgh_render::methods::lgh::tables::LghTables;
use lgh_render::shading::strata::ScreenStrata;
use rayon::prelude::*;

use lgh_core::lighting_grid::representative::SLOTS;

use lgh_render::shading::tiles::FlatBins;

use crate::batch::Batch;
use crate::bins::ListLayout;
use crate::context::{GpuContext, GpuError};
use crate::grid::LIGHT_FLOATS;
use crate::pool::Lease;

/// Hierarchies the uniform holds (the six normal bins, and room).
pub(super) const MAX_HIERARCHIES: usize = 8;

/// `Hier` of the shader: one hierarchy's place in the tables.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Hier {
    first: u32,
    grid_base: u32,
    lowest: u32,
    l_max: u32,
    origin: [f32; 3],
    h_top: f32,
    alpha: f32,
    rows_base: u32,
    starts_base: u32,
    children_base: u32,
    reps_base: u32,
    vpl_base: u32,
    _pad: [u32; 2],
}

/// `Params` of the shader.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct Params {
    pixels: u32,
    k: u32,
    hierarchies: u32,
    list_lights: u32,
    order: u32,
    pixel_lists: u32,
    eps2: f32,
    ray_eps: f32,
    seed_lo: u32,
    seed_hi: u32,
    /// The dithered strata's rotation c ([`ScreenStrata::key`]).
    strata_key: u32,
    /// Width x 256 + n x 2 + 1 with dithered strata, else 0 (`stratum_offset` in the shader).
    strata_shape: u32,
    hier: [Hier; MAX_HIERARCHIES],
}

/// The storage buffers' contents, where they are not the frame's tables themselves: the
/// lists and hierarchy buffers are uploaded from their parts ([`Tables::list_parts`],
/// [`Tables::word_parts`]) without a concatenated copy.
pub(super) struct Tables {
    /// Per shaded light: position and reach^2, normal and isotropic share, intensity and
    /// radius, blending floors with level and vertex x.
    pub(super) lights: Vec<[Vec4; 4]>,
    /// The pixels in the order the invocations take them ([`pixel_order`]), where the CPU
    /// binned the lights.
    order: Vec<u32>,
    /// Per hierarchy, its descent children as (child, bits of the running sum).
    children: Vec<Vec<u32>>,
    /// Each hierarchy's place in the words, the representatives and their VPLs.
    hier: Vec<Hier>,
    /// The words of all hierarchies.
    words: usize,
}

impl Tables {
    /// Packs `t` (its shaded lights only with `lights`: else the GPU made them,
    /// [`super::lights`]).
    pub(super) fn new(t: &LghTables, lights: bool) -> Result<Self, GpuError> {
        if t.hierarchies.len() > MAX_HIERARCHIES {
            return Err(GpuError::TooLarge(format!(
                "{} hierarchies (at most {MAX_HIERARCHIES})",
                t.hierarchies.len()
            )));
        }
        let all = if lights { t.lights } else { &[] };
        let mut lights: Vec<[Vec4; 4]> = all
            .par_iter()
            .map(|l| {
                let (rise, fall) = l.role.floors();
                // The top level's infinite reach as the largest float: the shader compares.
                let reach2 = l.reach2.min(f32::MAX);
                [
                    l.position.extend(reach2),
                    l.normal.extend(l.iso),
                    l.intensity.extend(l.radius),
                    Vec4::new(rise, fall, f32::from(l.level), 0.0),
                ]
            })
            .collect();
        let order = t.bins.as_ref().map_or_else(Vec::new, |b| {
            pixel_order(&b.list, b.offsets.len().saturating_sub(1))
        });
        let (mut words, mut vpls, mut slots, mut hier, mut children) =
            (0usize, 0usize, 0usize, Vec::new(), Vec::new());
        for h in &t.hierarchies {
            let grid = h.grid;
            if let Some(grid_lights) = lights.get_mut(h.grid_base as usize..) {
                grid_lights
                    .par_iter_mut()
                    .zip(&grid.vertex_x)
                    .for_each(|(light, &x)| light[3].w = f32::from_bits(x));
            }
            // Where the GPU makes the lookups (`lookups.rs`): the CPU's sizes, the children's
            // at most 27 a light of level >= 2.
            let on_device = grid.lookups_on_device;
            let rows_base = words as u32;
            words += if on_device {
                super::lookups::row_entries(grid.geometry.l_max)
            } else {
                grid.rows.iter().map(Vec::len).sum::<usize>()
            };
            let starts_base = words as u32;
            words += if on_device {
                grid.len + 1
            } else {
                h.descent_starts.len()
            };
            let children_base = words as u32;
            let pairs: Vec<u32> = h
                .descent_children
                .par_iter()
                .flat_map_iter(|&(c, sum)| [c, sum.to_bits()])
                .collect();
            words += if on_device {
                2 * super::lookups::MAX_CHILDREN * grid.len.saturating_sub(grid.s1_count)
            } else {
                pairs.len()
            };
            children.push(pairs);
            let reps_base = slots as u32;
            slots += SLOTS * grid.s1_count;
            let vpl_base = vpls as u32;
            vpls += grid.vpl_count;
            hier.push(Hier {
                first: h.first,
                grid_base: h.grid_base,
                lowest: grid.levels.lowest,
                l_max: grid.geometry.l_max,
                origin: grid.geometry.origin.into(),
                h_top: grid.geometry.h_top,
                alpha: grid.levels.alpha,
                rows_base,
                starts_base,
                children_base,
                reps_base,
                vpl_base,
                _pad: [0; 2],
            });
        }
        let limit = u32::MAX as usize / 2;
        if words > limit || slots > limit || vpls > limit / LIGHT_FLOATS {
            return Err(GpuError::TooLarge("hierarchy tables".into()));
        }
        Ok(Self {
            lights,
            order,
            children,
            hier,
            words,
        })
    }

    /// Where hierarchy `i`'s vertex rows, descent starts and descent children begin in the
    /// words.
    pub(super) fn word_bases(&self, i: usize) -> (u32, u32, u32) {
        let h = &self.hier[i];
        (h.rows_base, h.starts_base, h.children_base)
    }

    /// The lists buffer of the CPU's bins `bins` (these tables packed with them), laid out
    /// as [`ListLayout`]: the lists' starts, then their lights, then the pixels in the order
    /// the invocations take them, then each pixel's list.
    pub(super) fn list_parts<'s>(&'s self, bins: &'s FlatBins) -> Vec<&'s [u8]> {
        vec![
            bytemuck::cast_slice(&bins.offsets),
            bytemuck::cast_slice(&bins.lights),
            bytemuck::cast_slice(&self.order),
            bytemuck::cast_slice(&bins.list),
        ]
    }

    /// Where the parts of [`Tables::list_parts`] start.
    pub(super) fn list_layout(bins: &FlatBins) -> ListLayout {
        let lights = bins.offsets.len() as u32;
        let order = lights + bins.lights.len() as u32;
        ListLayout {
            lists: lights.saturating_sub(1),
            lights,
            order,
            pixel_lists: order + bins.list.len() as u32,
        }
    }

    /// One hierarchy's words as the CPU made them: its vertex-row starts of levels
    /// 1..=l_max, descent starts, and descent children as (child, bits of the running sum).
    fn word_parts<'s>(&'s self, t: &'s LghTables, i: usize) -> Vec<&'s [u8]> {
        let h = &t.hierarchies[i];
        let mut parts: Vec<&[u8]> = h
            .grid
            .rows
            .iter()
            .map(|r| bytemuck::cast_slice(r))
            .collect();
        parts.push(bytemuck::cast_slice(h.descent_starts));
        parts.push(bytemuck::cast_slice(&self.children[i]));
        parts
    }

    /// The hierarchy buffer (words), hierarchy after hierarchy, of `t` packed as these
    /// tables: the CPU's words uploaded; where the GPU makes a hierarchy's lookups
    /// ([`super::lookups`], recorded afterwards into `batch`), its place left for them and
    /// the CPU's parts of the others copied in by `batch`. (The S_1 lights'
    /// representatives and the VPLs they index are joined apart, [`super::held`].)
    ///
    /// # Errors
    /// A buffer cannot be had.
    pub(super) fn words<'c>(
        &self,
        ctx: &'c GpuContext,
        batch: &mut Batch<'c>,
        t: &LghTables,
    ) -> Result<Lease<'c>, GpuError> {
        let label = "hierarchy tables";
        let all = 0..t.hierarchies.len();
        if !t.hierarchies.iter().any(|h| h.grid.lookups_on_device) {
            let parts: Vec<&[u8]> = all.flat_map(|i| self.word_parts(t, i)).collect();
            return ctx.upload_parts(label, &parts);
        }
        let words = ctx.output(label, 4 * self.words as u64)?;
        for i in all.filter(|&i| !t.hierarchies[i].grid.lookups_on_device) {
            let parts = self.word_parts(t, i);
            let bytes: usize = parts.iter().map(|p| p.len()).sum();
            let part = ctx.upload_parts("hierarchy part", &parts)?;
            let at = 4 * u64::from(self.hier[i].rows_base);
            batch.copy(&part, 0, &words, at, bytes as u64);
            batch.keep(part);
        }
        Ok(words)
    }
}

impl Params {
    /// The uniform of a frame with inputs `i`, loop inputs `t`, packed tables `p` and lists
    /// laid out as `lists`.
    pub(super) fn new(
        i: &MethodInputs,
        t: &LghTables,
        p: &Tables,
        lists: ListLayout,
    ) -> Result<Self, GpuError> {
        let mut hier = [Hier::default(); MAX_HIERARCHIES];
        hier[..p.hier.len()].copy_from_slice(&p.hier);
        let seed = i.settings.seed;
        let (strata_key, strata_shape) = if i.settings.lgh.selection == Selection::Dithered {
            let strata = ScreenStrata::new(seed, t.n);
            let width = i.gbuffer.width;
            if width >= 1 << 24 || strata.phases >= 128 {
                return Err(GpuError::TooLarge(
                    "the dithered strata's image width".into(),
                ));
            }
            (strata.key, width << 8 | strata.phases << 1 | 1)
        } else {
            (0, 0)
        };
        Ok(Self {
            pixels: u32::try_from(i.gbuffer.len())
                .map_err(|_| GpuError::TooLarge("pixels".into()))?,
            k: t.k,
            hierarchies: p.hier.len() as u32,
            list_lights: lists.lights,
            order: lists.order,
            pixel_lists: lists.pixel_lists,
            eps2: t.eps2,
            ray_eps: i.world.ray_epsilon,
            seed_lo: seed as u32,
            seed_hi: (seed >> 32) as u32,
            strata_key,
            strata_shape,
            hier,
        })
    }
}

/// The pixels sorted by their light list (a counting sort, stable): consecutive invocations,
/// and so the threads of a workgroup, shade pixels of one (sub-image, tile) and read the
/// same lights, instead of a row's pixels cycling through n^2 sub-images and several tiles.
/// Each pixel's result depends on its own index only, so the order changes no value.
fn pixel_order(list: &[u32], lists: usize) -> Vec<u32> {
    let mut start = vec![0u32; lists + 1];
    for &l in list {
        start[(l as usize).min(lists)] += 1;
    }
    let mut at = 0;
    for s in &mut start {
        (*s, at) = (at, at + *s);
    }
    let mut order = vec![0u32; list.len()];
    for (p, &l) in list.iter().enumerate() {
        let slot = &mut start[(l as usize).min(lists)];
        order[*slot as usize] = p as u32;
        *slot += 1;
    }
    order
}
