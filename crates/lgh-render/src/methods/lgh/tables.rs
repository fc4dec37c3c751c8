//! The `lgh` lighting loop's inputs as flat tables, for a backend that runs the loop
//! elsewhere (lgh-gpu): the shaded lights, one light list per pixel, and per hierarchy what
//! the unbiased estimate's shadow targets read (docs/design.md, "Unbiased estimate"): the
//! vertex rows that find a grid light's centroid for Lambda_i, the children of every light
//! for the walk down to S_1, and the S_1 lights' representatives.

use glam::Vec3;
use lgh_core::lighting_grid::geometry::GridGeometry;
use lgh_core::lighting_grid::lookup::row_starts;
use lgh_core::lighting_grid::partition::ShadedLevels;
use lgh_core::lighting_grid::representative::SLOTS;
use lgh_core::lighting_grid::{GridShape, LightingGrid};

use lgh_core::vpl::Vpls;
use rayon::prelude::*;

use super::LghFrame;
use super::light_batch::PackedLight;
use super::rep_set::chroma;
use crate::shading::tiles::FlatBins;

/// One hierarchy's grid as flat tables: its geometry and shaded levels, the x coordinate
/// of every grid light's vertex, per level l >= 1 where each vertex row starts
/// ([`row_starts`]: a vertex's light is found in its row by its x), the representatives of
/// its S_1 lights as indices into its VPLs, and those VPLs.
#[derive(Clone, Debug)]
pub struct GridTables {
    /// The grid's geometry (origin, top cell size, l_max).
    pub geometry: GridGeometry,
    /// The shaded levels (lowest, alpha).
    pub levels: ShadedLevels,
    /// Per grid light, the x coordinate of its vertex; empty where the builder keeps the
    /// grid on its device ([`GridTables::lookups_on_device`]).
    pub vertex_x: Vec<u32>,
    /// Per level l = 1..=l_max (index l - 1), the row starts; empty where the builder's
    /// device makes them ([`GridTables::lookups_on_device`]).
    pub rows: Vec<Vec<u32>>,
    /// Whether the builder's device makes the vertex rows and the descent's children
    /// itself from its copy of the grid
    /// ([`lgh_core::lighting_grid::HierarchyBuilder::makes_lookups`]): `rows` and the
    /// hierarchy's descent tables are then empty.
    pub lookups_on_device: bool,
    /// The number of grid lights.
    pub len: usize,
    /// Per S_1 light (by grid index), its [`SLOTS`] representatives: indices into `vpls`,
    /// [`lgh_core::lighting_grid::representative::NONE`] for an empty slot; empty where the
    /// builder keeps them on its device
    /// ([`lgh_core::lighting_grid::HierarchyBuilder::keeps_representatives`]).
    pub rep_vpls: Vec<[u32; SLOTS]>,
    /// The number of S_1 lights (`rep_vpls.len()` unless the builder keeps them).
    pub s1_count: usize,
    /// The VPLs the hierarchy was built from; empty where its builder keeps them on its
    /// device ([`lgh_core::lighting_grid::HierarchyBuilder::keeps_lights`]).
    pub vpls: Vec<RepSlot>,
    /// How many VPLs the hierarchy was built from (`vpls.len()` unless they are kept).
    pub vpl_count: usize,
}

impl GridTables {
    /// The tables of `grid`, built from `vpls` and shaded at `levels`, with its S_1
    /// lights' representatives `rep_vpls`; without a copy of the VPLs, nor the vertex
    /// rows, where the builder `keeps` them.
    #[must_use]
    pub(super) fn new(
        grid: &LightingGrid,
        levels: ShadedLevels,
        rep_vpls: impl Iterator<Item = [u32; SLOTS]>,
        vpls: &Vpls,
        keeps: DeviceKeeps,
    ) -> Self {
        let rows = if keeps.lookups { 0 } else { grid.l_max() };
        Self {
            geometry: grid.geometry,
            levels,
            vertex_x: grid.vertex.par_iter().map(|v| v.x).collect(),
            rows: (1..=rows).map(|l| row_starts(grid, l)).collect(),
            lookups_on_device: keeps.lookups,
            len: grid.len(),
            rep_vpls: rep_vpls.collect(),
            s1_count: grid.level_range(1).len(),
            vpl_count: vpls.len(),
            vpls: (0..if keeps.lights { 0 } else { vpls.len() })
                .into_par_iter()
                .map(|i| RepSlot {
                    position: vpls.positions[i],
                    normal: vpls.normals[i],
                    colour: chroma(vpls.flux[i]),
                })
                .collect(),
        }
    }

    /// The tables of a grid of shape `shape` that its builder keeps on its device, with
    /// everything the device makes there (`DeviceKeeps` all true): built from `vpl_count`
    /// VPLs and shaded at `levels`; no array is made on the CPU.
    #[must_use]
    pub(super) fn on_device(shape: &GridShape, levels: ShadedLevels, vpl_count: usize) -> Self {
        Self {
            geometry: shape.geometry,
            levels,
            vertex_x: Vec::new(),
            rows: Vec::new(),
            lookups_on_device: true,
            len: shape.len(),
            rep_vpls: Vec::new(),
            s1_count: shape.level_range(1).len(),
            vpls: Vec::new(),
            vpl_count,
        }
    }
}

/// What a hierarchy builder's device keeps of its last build for a frame whose loop runs
/// there ([`lgh_core::lighting_grid::HierarchyBuilder::keeps_lights`],
/// [`keeps_representatives`](lgh_core::lighting_grid::HierarchyBuilder::keeps_representatives),
/// [`makes_lookups`](lgh_core::lighting_grid::HierarchyBuilder::makes_lookups)): the CPU
/// does not make these.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct DeviceKeeps {
    /// The build's input lights (the VPLs the representatives index).
    pub lights: bool,
    /// The S_1 lights' representatives.
    pub representatives: bool,
    /// The vertex rows and the descent's children.
    pub lookups: bool,
}

/// A VPL as the unbiased estimate's targets read it: position, normal and the colour of its
/// flux (at unit luminance).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RepSlot {
    /// Position.
    pub position: Vec3,
    /// Normal.
    pub normal: Vec3,
    /// Flux colour.
    pub colour: Vec3,
}

/// What the unbiased estimate reads of one hierarchy.
#[derive(Clone, Debug)]
pub struct HierarchyTables<'a> {
    /// Index among the shaded lights of the hierarchy's first light.
    pub first: u32,
    /// Index among the shaded lights of its grid light 0 (after its VPLs if they are shaded).
    pub grid_base: u32,
    /// Its grid, representatives and VPLs.
    pub grid: &'a GridTables,
    /// Light j's children are `children[starts[j]..starts[j + 1]]` (grid indices).
    pub descent_starts: &'a [u32],
    /// (child, running sum of the weights).
    pub descent_children: &'a [(u32, f32)],
}

/// The lighting loop's inputs of one frame ([`LghFrame::tables`]).
#[derive(Clone, Debug)]
pub struct LghTables<'a> {
    /// The shaded lights (intensities times n^2 for n x n interleaving); empty where the
    /// hierarchies' builder keeps them on its device (`light_count` of them).
    pub lights: &'a [PackedLight],
    /// The number of shaded lights.
    pub light_count: usize,
    /// The light list of every pixel; `None` if the frame's lights are not binned on the
    /// CPU ([`LghFrame::bin_on_cpu`]).
    pub bins: Option<FlatBins>,
    /// Per hierarchy, the unbiased estimate's tables (empty without shadow samples).
    pub hierarchies: Vec<HierarchyTables<'a>>,
    /// Shadow samples per pixel.
    pub k: u32,
    /// Interleaving n.
    pub n: u32,
    /// eps^2 of the 1/d^2 clamp.
    pub eps2: f32,
}

impl LghFrame {
    /// The lighting loop's inputs as flat tables for a `width` x `height` G-buffer (the
    /// frame's). The hierarchies' tables are there if the frame was prepared with them
    /// ([`LghFrame::prepare`]) for the unbiased estimate; `None` if it was not.
    #[must_use]
    pub fn tables(&self, width: u32, height: u32) -> Option<LghTables<'_>> {
        let mut hierarchies = Vec::new();
        for h in &self.lights.hierarchies {
            let (descent_starts, descent_children) = h.descent.tables();
            hierarchies.push(HierarchyTables {
                first: h.first as u32,
                grid_base: h.grid_base as u32,
                grid: h.tables.as_ref()?,
                descent_starts,
                descent_children,
            });
        }
        Some(LghTables {
            lights: &self.packed,
            light_count: self.lights.len(),
            bins: self.bins.as_ref().map(|b| b.flatten(width, height)),
            hierarchies,
            k: self.k as u32,
            n: self.n,
            eps2: self.eps2,
        })
    }
}
