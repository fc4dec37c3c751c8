//! The lights the LGH lighting loop shades: the grid lights of the shaded levels (and the
//! VPLs as S_0), structure of arrays, with each light's level radius r_l, blending role and
//! reach, and the representative VPLs its shadow rays go to.

use glam::Vec3;
use lgh_core::blending::LevelRole;
use lgh_core::lighting_grid::descent::Descent;
use lgh_core::lighting_grid::lookup::{VertexLookup, VertexRows};
use lgh_core::lighting_grid::partition::{Partition, ShadedLevels, quantized_emission};
use lgh_core::lighting_grid::representative::{SLOTS, representatives, s1_representatives};
use lgh_core::lighting_grid::{Construction, GridError, GridShape, LightingGrid};
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::vpl::{GridEmission, Vpls};
use rayon::prelude::*;

use crate::methods::lgh::light_batch::PackedLight;
use crate::methods::lgh::rep_set::{RepSet, chroma, relative_colour, representative_weight};
use crate::methods::lgh::tables::{DeviceKeeps, GridTables};
use crate::passes::gbuffer::GBuffer;
use crate::shading::reservoirs::{ShadowReservoirs, ShadowSample};
use crate::shading::shadow_pass::Targets;
use crate::shading::tiles::emission_facing;

/// Random-stream tag of the shadow targets drawn after selection.
const STREAM_TARGET: u64 = 0x162;

/// Samples of the unbiased estimate whose targets are drawn together
/// ([`ShadeLights::resolve_unbiased`]).
const TARGET_BATCH: usize = 16;

/// A sample of the unbiased estimate on its way to its target: the grid light its walk has
/// reached (`None` for a VPL shaded as S_0), in hierarchy `hierarchy`.
struct Pending<'a> {
    sample: &'a mut ShadowSample,
    pixel: usize,
    rng: Rng,
    hierarchy: usize,
    node: Option<usize>,
    walking: bool,
}

/// The lights a pixel may see, structure-of-arrays, each with its level's radius r_l,
/// blending role and reach (2 r_l, or infinite for the top level).
#[derive(Default)]
pub(super) struct ShadeLights {
    pub(super) position: Vec<Vec3>,
    pub(super) normal: Vec<Vec3>,
    /// Isotropic share of the emission cosine ([`GridEmission::isotropic`]).
    pub(super) iso: Vec<f32>,
    pub(super) intensity: Vec<Vec3>,
    pub(super) deviation: Vec<Vec3>,
    pub(super) level: Vec<u8>,
    /// Sub-image of interleaved sampling: within each level, light k goes to k mod n^2.
    pub(super) sub: Vec<u16>,
    pub(super) radius: Vec<f32>,
    pub(super) role: Vec<LevelRole>,
    pub(super) reach: Vec<f32>,
    /// The [`SLOTS`] representative VPLs of each light (shadow target `Representative`;
    /// empty otherwise).
    reps: Vec<RepSet>,
    /// What the unbiased estimate needs of each hierarchy (empty for the paper's).
    pub(super) hierarchies: Vec<Hierarchy>,
    /// The lights a builder's device holds and makes the loop's rows of itself (none of
    /// them in the arrays above, which are then empty: [`ShadeLights::add_on_device`]).
    on_device: usize,
}

impl ShadeLights {
    /// What the tile binning culls each light by besides its sphere: the normal of the
    /// plane behind which it gives nothing ([`emission_facing`]), and the distance within
    /// which its blending weight is zero ([`LevelRole::hole`]).
    pub(super) fn bin_extras(&self) -> (Vec<Vec3>, Vec<f32>) {
        let facing = (self.normal.par_iter().zip(&self.iso))
            .map(|(&m, &iso)| emission_facing(m, iso))
            .collect();
        let holes = (self.role.par_iter().zip(&self.radius))
            .map(|(&role, &r)| role.hole(r))
            .collect();
        (facing, holes)
    }
}

/// One hierarchy as the unbiased estimate reads it (docs/design.md, "Unbiased estimate"):
/// its centroids by vertex for Lambda_i, the children of its lights for the draw of an S_1
/// light, and the S_1 lights' representatives (with their VPLs' colours).
pub(super) struct Hierarchy {
    /// The representatives of its S_1 lights (by grid index); empty in a frame prepared with
    /// tables (whose loop runs on another backend, reading the tables' slots).
    reps: Vec<RepSet>,
    /// Lambda_i's lookup for the CPU's loop; `None` in a frame prepared with tables (the
    /// other backend finds Lambda_i from the tables' vertex rows).
    partition: Option<Partition>,
    pub(super) descent: Descent,
    /// Index in [`ShadeLights`] of the hierarchy's first light.
    pub(super) first: usize,
    /// Index in [`ShadeLights`] of its grid light 0 (after the VPLs if they are shaded).
    pub(super) grid_base: usize,
    /// Its lookup tables as flat arrays, when the frame is prepared for another backend.
    pub(super) tables: Option<GridTables>,
}

impl ShadeLights {
    /// The number of shaded lights.
    pub(super) fn len(&self) -> usize {
        self.position.len() + self.on_device
    }

    /// Counts the lights of a hierarchy of shape `shape` built from `vpls` VPLs, shaded from
    /// level `lowest` (0: the VPLs too), whose builder keeps it on its device and makes the
    /// loop's rows there: none is added to the arrays.
    ///
    /// # Errors
    /// Lights of a hierarchy the CPU holds are here already (the indices would not match).
    pub(super) fn add_on_device(
        &mut self,
        shape: &GridShape,
        vpls: usize,
        lowest: u32,
    ) -> Result<(), GridError> {
        if !self.position.is_empty() {
            return Err(GridError::KeptOnDevice);
        }
        self.on_device += shape.len() + if lowest == 0 { vpls } else { 0 };
        Ok(())
    }

    /// Adds levels `lowest..=l_max` of `grid` (level 0 = the VPLs `vpls` it was built from).
    ///
    /// # Errors
    /// Lights a builder's device holds are here already (the indices would not match).
    pub(super) fn add_hierarchy(
        &mut self,
        grid: &LightingGrid,
        vpls: &Vpls,
        lowest: u32,
        alpha: f32,
        emission: GridEmission,
        n2: usize,
    ) -> Result<(), GridError> {
        if self.on_device > 0 {
            return Err(GridError::KeptOnDevice);
        }
        let geom = grid.geometry;
        let l_max = geom.l_max;
        for l in lowest..=l_max {
            let r = if l == 0 { 0..0 } else { grid.level_range(l) };
            let (p, n, i, d) = if l == 0 {
                (&vpls.positions[..], &vpls.normals[..], &vpls.flux[..], None)
            } else {
                (
                    &grid.position[r.clone()],
                    &grid.normal[r.clone()],
                    &grid.intensity[r.clone()],
                    Some(&grid.deviation[r]),
                )
            };
            let radius = geom.radius(l, alpha);
            let role = LevelRole::of(l, lowest, l_max);
            self.position.extend_from_slice(p);
            self.normal.extend_from_slice(n);
            self.iso.extend(n.iter().map(|&m| emission.isotropic(m)));
            self.intensity.extend_from_slice(i);
            match d {
                Some(d) => self.deviation.extend_from_slice(d),
                None => self
                    .deviation
                    .extend(std::iter::repeat_n(Vec3::ZERO, p.len())),
            }
            self.level.extend(std::iter::repeat_n(l as u8, p.len()));
            self.sub.extend((0..p.len()).map(|k| (k % n2) as u16));
            self.radius.extend(std::iter::repeat_n(radius, p.len()));
            self.role.extend(std::iter::repeat_n(role, p.len()));
            self.reach
                .extend(std::iter::repeat_n(role.reach(radius), p.len()));
        }
        Ok(())
    }

    /// Leaves only the lights of level `level` in view: the others get a negative reach,
    /// which the tile binning skips, so no pixel shades them and none is a shadow candidate
    /// (their indices, which the unbiased estimate's walk uses, stay as they are).
    pub(super) fn show_only_level(&mut self, level: u32) {
        for (reach, &l) in self.reach.iter_mut().zip(&self.level) {
            if u32::from(l) != level {
                *reach = -1.0;
            }
        }
    }

    /// Adds the representatives of the lights that [`ShadeLights::add_hierarchy`] added for
    /// the same `grid` and `lowest` level: [`SLOTS`] per light, drawn for the shadow
    /// candidates (levels >= `from_level`; a VPL of level 0 is its own), empty slots
    /// elsewhere.
    pub(super) fn add_representatives(
        &mut self,
        grid: &LightingGrid,
        vpls: &Vpls,
        lowest: u32,
        from_level: u32,
        construction: Construction,
        seed: u64,
    ) {
        let reps = representatives(grid, &vpls.as_input(), from_level, construction, seed);
        if lowest == 0 {
            // A VPL stands for itself.
            self.reps.extend((0..vpls.len()).map(|i| {
                let mut set = RepSet::default();
                for s in 0..SLOTS {
                    set.set(s, vpls.positions[i], vpls.normals[i], vpls.flux[i]);
                }
                set
            }));
        }
        let first = grid.level_range(1).start;
        self.reps.extend(
            reps[SLOTS * first..]
                .chunks(SLOTS)
                .map(|slots| RepSet::of(slots, vpls)),
        );
    }

    /// Keeps what the unbiased estimate needs of `grid` (built from `vpls`, `count` of them
    /// (`vpls` is empty where the builder's device keeps them), by restriction or
    /// all-scatter; `None` where its builder keeps it on its device, of shape `shape`),
    /// whose lights [`ShadeLights::add_hierarchy`] added from index `first` with levels
    /// `levels`: the representatives of its S_1 lights (drawn with `seed`, or `drawn`
    /// already where the builder drew them), the children of its coarser lights and its
    /// centroids by vertex. With `tables`, what the builder's device keeps (`keeps`) is not
    /// made: a copy of the VPLs, the representatives, the lookups. Without `grid`, the
    /// caller has checked that the device keeps all of them.
    pub(super) fn add_unbiased(
        &mut self,
        (grid, shape): (Option<&LightingGrid>, &GridShape),
        (vpls, count): (&Vpls, usize),
        levels: ShadedLevels,
        (seed, drawn): (u64, Option<&[[u32; SLOTS]]>),
        first: usize,
        (tables, keeps): (bool, DeviceKeeps),
    ) {
        // S_1 only: the draw below a coarser light is made afresh per sample. With tables the
        // frame is for another backend's loop, which reads the slots' VPL indices (the GPU
        // reads the VPLs by index); only the CPU's loop reads them as `RepSet`s (576 bytes
        // an S_1 light), which are then not made.
        let drawn = drawn.filter(|d| d.len() == shape.level_range(1).len());
        let input = vpls.as_input();
        let vpl_lights = if levels.lowest == 0 { count } else { 0 };
        // The grid lights' isotropic shares, as add_hierarchy made them for the loop.
        let grid_base = first + vpl_lights;
        let iso = &self.iso;
        // The three parts are independent: made side by side, so that one's serial steps
        // (sorts, prefix sums, allocations) overlap another's parallel ones.
        let representatives = || -> (Vec<RepSet>, Vec<[u32; SLOTS]>) {
            match (tables, drawn, grid) {
                (true, _, _) if keeps.representatives => (Vec::new(), Vec::new()),
                (true, Some(d), _) => (Vec::new(), d.to_vec()),
                (true, None, Some(grid)) => {
                    (Vec::new(), s1_representatives(grid, &input, seed, |s| *s))
                }
                (false, Some(d), _) => (
                    d.par_iter().map(|s| RepSet::of(s, vpls)).collect(),
                    Vec::new(),
                ),
                (false, None, Some(grid)) => (
                    s1_representatives(grid, &input, seed, |s| RepSet::of(s, vpls)),
                    Vec::new(),
                ),
                (_, None, None) => (Vec::new(), Vec::new()),
            }
        };
        // The walk's children, unless the device makes them from its own copy of the grid.
        let descent = || match grid {
            Some(grid) if !(tables && keeps.lookups) => {
                Descent::new(VertexLookup::new(grid, &VertexRows::new(grid)))
            }
            _ => Descent::default(),
        };
        let partition = || {
            grid.filter(|_| !tables).map(|grid| {
                let iso = &iso[grid_base..grid_base + grid.position.len()];
                Partition::new(grid, levels, iso)
            })
        };
        let ((reps, slots), (descent, partition)) =
            rayon::join(representatives, || rayon::join(descent, partition));
        self.hierarchies.push(Hierarchy {
            reps,
            partition,
            descent,
            first,
            grid_base,
            tables: tables.then(|| match grid {
                Some(grid) => GridTables::new(grid, levels, slots.into_iter(), vpls, keeps),
                None => GridTables::on_device(shape, levels, count),
            }),
        });
    }

    /// Representative `s` of light `j`: its position and normal, or `None` for an empty slot.
    pub(super) fn representative(&self, j: usize, s: usize) -> Option<(Vec3, Vec3)> {
        let (q, nq) = self.reps[j].get(s);
        (nq != Vec3::ZERO).then_some((q, nq))
    }

    /// Draws the shadow target of every selected sample among its light's representatives in
    /// proportion to their unshadowed contributions at the pixel (as VPLs of the light's
    /// intensity); drops the sample if none contributes.
    pub(super) fn resolve_representatives(
        &self,
        reservoirs: &mut ShadowReservoirs,
        g: &GBuffer,
        seed: u64,
        eps2: f32,
    ) {
        let w = g.width as usize;
        if !self.hierarchies.is_empty() {
            let (k, slots) = (reservoirs.k(), reservoirs.slots());
            reservoirs.groups_mut(1).for_each(|(y, row)| {
                let mut batch = Vec::with_capacity(TARGET_BATCH);
                for (x, pixel) in row.chunks_mut(slots).enumerate() {
                    let i = y * w + x;
                    if !g.is_hit(i) {
                        continue;
                    }
                    for (r, res) in pixel[..k].iter_mut().enumerate() {
                        if let Some(sample) = res.sample.as_mut() {
                            let rng = Rng::new(&[seed, i as u64, STREAM_TARGET, r as u64]);
                            batch.push(self.pending(sample, i, rng));
                            if batch.len() == TARGET_BATCH {
                                self.resolve_unbiased(&mut batch, g, eps2);
                            }
                        }
                    }
                }
                self.resolve_unbiased(&mut batch, g, eps2);
            });
            return;
        }
        let layout = reservoirs.layout();
        reservoirs.groups_mut(1).for_each(|(y, row)| {
            for x in 0..w {
                let i = y * w + x;
                if g.is_hit(i) {
                    let mut rng = Rng::new(&[seed, i as u64, STREAM_TARGET]);
                    for r in layout.pixel_mut(row, x) {
                        self.resolve_representative(r, g.position[i], g.normal[i], &mut rng, eps2);
                    }
                }
            }
        });
    }

    /// Draws the target of a sample of the paper's estimate among its light's
    /// representatives, in proportion to their contributions at the pixel at `xp` with
    /// normal `nx`.
    fn resolve_representative(
        &self,
        r: &mut Reservoir<ShadowSample>,
        xp: Vec3,
        nx: Vec3,
        rng: &mut Rng,
        eps2: f32,
    ) {
        let Some(j) = r.sample.map(|s| s.light as usize) else {
            return;
        };
        // The representatives' contributions (an empty slot has n_q = 0).
        let weights = self.reps[j].weights(xp, nx, eps2);
        let total: f32 = weights.iter().sum();
        if total <= 0.0 {
            // None of the VPLs the light stands for lights the pixel: its contribution
            // is an artefact of the mean normal, with no visibility to estimate.
            // Dropped, as a zero weight drops it at candidate time.
            r.sample = None;
            return;
        }
        let pick = pick_weighted(&weights, total, rng.next_f32());
        if let Some(sample) = r.sample.as_mut() {
            (sample.q, sample.n) = self.reps[j].get(pick);
        }
    }

    /// A sample of pixel `pixel` whose unbiased target is still to be drawn: its hierarchy,
    /// and the grid light its walk starts from (`None` for a VPL shaded as S_0).
    fn pending<'a>(&self, sample: &'a mut ShadowSample, pixel: usize, rng: Rng) -> Pending<'a> {
        let j = sample.light as usize;
        let hierarchy = self.hierarchy_index(j);
        let base = self.hierarchies[hierarchy].grid_base;
        // No ray unless a VPL below j lights the pixel (U still counts j).
        sample.gain = Vec3::ZERO;
        Pending {
            sample,
            pixel,
            rng,
            hierarchy,
            node: j.checked_sub(base),
            walking: j >= base,
        }
    }

    /// Draws the targets of a batch of samples of the unbiased estimate (docs/design.md,
    /// "Unbiased estimate") and empties the batch: from each sample's light j (a VPL, or grid
    /// light g of some level) an S_1 light below it in proportion to its share
    /// ([`Descent`]; j itself for S_1 and VPLs), and one of that light's representatives i
    /// in proportion to its unshadowed contribution rho_i at the pixel; the ray goes to VPL
    /// i. The sample's gain S_k / U_k per unit visibility is (sum rho / SLOTS) /
    /// (G_j Lambda_i) in the colour of VPL i: the ratio of the VPL's share-weighted
    /// contribution, as a sample of the VPLs that j stands for, to j's own contribution
    /// A_j = B_l I_j G_j / pi. Here the gain gets the colour and sum rho / SLOTS; G_j and
    /// Lambda_i, which only a visible sample needs, divide it in
    /// [`ShadeLights::unbiased_gain`] once the ray has found the target visible. The gain is
    /// zero (no ray) if no representative lights the pixel (U still counts the light: it
    /// is part of A).
    ///
    /// The batch goes through each step together, so that its samples' reads of memory
    /// (the children of each level, then the representatives) are independent loads in
    /// flight at once, not one sample's chain of cache misses after another's (docs/design.md,
    /// "Unbiased estimate").
    fn resolve_unbiased(&self, batch: &mut Vec<Pending>, g: &GBuffer, eps2: f32) {
        // The walks, one level a round for every sample still walking.
        loop {
            let mut moved = false;
            for p in batch.iter_mut().filter(|p| p.walking) {
                let descent = &self.hierarchies[p.hierarchy].descent;
                let u = p.rng.next_f32();
                match p.node.and_then(|node| descent.child(node, u)) {
                    Some(c) => (p.node, moved) = (Some(c), true),
                    None => p.walking = false,
                }
            }
            if !moved {
                break;
            }
        }
        // Every representative set the batch will weigh, read once ahead: six cache lines of
        // positions and normals and three of colours each.
        let mut touch = 0.0;
        for p in batch.iter() {
            if let Some(reps) = p
                .node
                .and_then(|u| self.hierarchies[p.hierarchy].reps.get(u))
            {
                touch += reps.touch();
            }
        }
        std::hint::black_box(touch);
        for p in batch.drain(..) {
            let (xp, nx) = (g.position[p.pixel], g.normal[p.pixel]);
            let sample = p.sample;
            let (q, nq, colour, mean_rho) = match p.node {
                None => {
                    // A VPL shaded as S_0 stands for itself, in its own colour.
                    let j = sample.light as usize;
                    let (q, nq) = (self.position[j], self.normal[j]);
                    let rho = representative_weight(xp, nx, q, nq, eps2);
                    (q, nq, Vec3::ONE, rho)
                }
                Some(u) => {
                    let mut rng = p.rng;
                    // (A frame prepared with tables has no CPU copies; its loop runs
                    // elsewhere.)
                    let Some(reps) = self.hierarchies[p.hierarchy].reps.get(u) else {
                        continue;
                    };
                    let weights = reps.weights(xp, nx, eps2);
                    let total: f32 = weights.iter().sum();
                    if total <= 0.0 {
                        continue;
                    }
                    let pick = pick_weighted(&weights, total, rng.next_f32());
                    let (q, nq) = reps.get(pick);
                    // The colour of j is that of its contribution f (a scalar multiple of its
                    // intensity), already at hand: reading I_j would be one more wait on
                    // memory.
                    let colour = relative_colour(reps.colour(pick), chroma(sample.f));
                    (q, nq, colour, total / SLOTS as f32)
                }
            };
            if mean_rho > 0.0 {
                (sample.q, sample.n) = (q, nq);
                sample.gain = colour * mean_rho;
            }
        }
    }

    /// The index of the hierarchy light `j` belongs to.
    fn hierarchy_index(&self, j: usize) -> usize {
        self.hierarchies.partition_point(|h| h.first <= j) - 1
    }

    /// The hierarchy light `j` belongs to.
    fn hierarchy_of(&self, j: usize) -> &Hierarchy {
        &self.hierarchies[self.hierarchy_index(j)]
    }

    /// The gain of a visible sample of the unbiased estimate at the pixel at `xp` with
    /// normal `nx`: the gain [`ShadeLights::resolve_unbiased`] set, divided by Lambda_i (the
    /// sum of its VPL's shares weighted by their grid lights' geometry terms) and multiplied
    /// by the drawn light's emission cosine as the partition stores it over its own (zero
    /// where Lambda_i is, and where the drawn light's level is not admitted at the VPL's
    /// distance, [`Partition::admits`]; docs/design.md, "Unbiased estimate").
    fn unbiased_gain(&self, sample: &ShadowSample, xp: Vec3, nx: Vec3, eps2: f32) -> Vec3 {
        let j = sample.light as usize;
        let hierarchy = self.hierarchy_of(j);
        let Some(partition) = &hierarchy.partition else {
            return Vec3::ZERO;
        };
        // A VPL shaded as S_0 is weighed with its own geometry term, a grid light with its
        // emission as the partition stores it. (Checked before Lambda_i, which a sample of
        // a level not admitted does not need.)
        let cosines = if j < hierarchy.grid_base {
            1.0
        } else if !partition.admits(u32::from(self.level[j]), xp, sample.q) {
            // Light i's shares are among the levels admitted at its own distance only.
            return Vec3::ZERO;
        } else {
            let w = (self.position[j] - xp).normalize_or_zero();
            let (m, iso) = quantized_emission(self.normal[j], self.iso[j]);
            let stored = (-m.dot(w)).max(0.0) + iso;
            stored / ((-self.normal[j].dot(w)).max(0.0) + self.iso[j])
        };
        let lambda = partition.share_total(xp, nx, sample.q, sample.n, eps2);
        if lambda <= 0.0 {
            return Vec3::ZERO;
        }
        let gain = sample.gain * (cosines / lambda);
        // A Lambda_i near the float minimum (every grid light of the VPL at a grazing angle)
        // belongs to a contribution near it too; an overflowed gain, or a drawn light with
        // no emission towards the pixel, would turn the filter's sums into NaN.
        Vec3::select(gain.is_finite_mask(), gain, Vec3::ZERO)
    }

    /// The lights packed for the lighting loop, intensities times `scale`.
    pub(super) fn packed(&self, scale: f32) -> Vec<PackedLight> {
        (0..self.position.len())
            .into_par_iter()
            .map(|j| PackedLight {
                position: self.position[j],
                reach2: self.reach[j] * self.reach[j],
                normal: self.normal[j],
                iso: self.iso[j],
                intensity: self.intensity[j] * scale,
                radius: self.radius[j],
                role: self.role[j],
                level: self.level[j],
            })
            .collect()
    }
}

/// The shadow targets of `lgh`'s lights, drawn after selection ([`ShadeLights`]'s
/// representatives or unbiased estimate) for the pixels of `g`.
pub(super) struct LghTargets<'a> {
    pub(super) lights: &'a ShadeLights,
    pub(super) g: &'a GBuffer,
    pub(super) seed: u64,
    pub(super) eps2: f32,
}

impl Targets for LghTargets<'_> {
    fn resolve(&self, reservoirs: &mut ShadowReservoirs) {
        self.lights
            .resolve_representatives(reservoirs, self.g, self.seed, self.eps2);
    }

    fn visible_gain(&self, pixel: usize, sample: &ShadowSample) -> Vec3 {
        if self.lights.hierarchies.is_empty() {
            return sample.gain;
        }
        let (xp, nx) = (self.g.position[pixel], self.g.normal[pixel]);
        self.lights.unbiased_gain(sample, xp, nx, self.eps2)
    }
}

/// The index drawn from `weights` (summing to `total` > 0) with the uniform number `u`.
fn pick_weighted(weights: &[f32; SLOTS], total: f32, u: f32) -> usize {
    let mut u = u * total;
    for (s, &wt) in weights.iter().enumerate() {
        if u < wt {
            return s;
        }
        u -= wt;
    }
    SLOTS - 1
}
