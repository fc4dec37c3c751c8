//! The frame's VPLs kept on the GPU for its hierarchy build: the light-path kernel's VPLs
//! are read back (the CPU's half of the frame needs them), and also written in the layout
//! the build reads (`shaders/vpl_grid.wgsl`), so that the build need not upload them again
//! ([`crate::grid::GpuGridBuilder`] takes them).
//!
//! They are known by the read-back VPLs they stand for: the addresses and length of their
//! arrays and the bits of their first and last VPL. Only a GPU method's frame keeps them
//! ([`super::method_vpls`], which first drops whatever an earlier frame left), and the
//! build takes them (whether it uses them or not), so they never outlive the frame that
//! made them into another's.
//!
//! A frame whose every pass after the VPLs runs on the GPU does not read them back at all
//! ([`Held`]): the CPU gets their number (the frame's
//! [`VplSet::kept`](lgh_render::passes::vpl_gen::VplSet::kept)), and the build their
//! bounds, found on the GPU, through
//! [`HierarchyBuilder::build_held`](lgh_core::lighting_grid::HierarchyBuilder::build_held).
//! The VPLs as the light-path kernel wrote them
//! stay too, for a frame that has to be made again with its grids on the CPU
//! ([`take_records`]).

use std::sync::{Mutex, PoisonError};
use std::thread::ThreadId;

use glam::Vec3;
use lgh_core::lighting_grid::InputLights;

use crate::context::GpuContext;
use crate::pool::{Detached, Lease};

/// What the kept lights stand for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Key {
    arrays: [usize; 3],
    len: usize,
    ends: [u32; 12],
}

impl Key {
    /// The key of the build's input `lights`.
    pub(crate) fn of(lights: &InputLights) -> Self {
        let n = lights.positions.len();
        let bits = |v: Option<&Vec3>| v.copied().unwrap_or(Vec3::NAN).to_array().map(f32::to_bits);
        let [a, b, c] = bits(lights.positions.first());
        let [d, e, f] = bits(lights.positions.last());
        let [g, h, i] = bits(lights.intensity.first());
        let [j, k, l] = bits(lights.intensity.last());
        Self {
            arrays: [
                lights.positions.as_ptr() as usize,
                lights.intensity.as_ptr() as usize,
                lights.normals.map_or(0, |m| m.as_ptr() as usize),
            ],
            len: n,
            ends: [a, b, c, d, e, f, g, h, i, j, k, l],
        }
    }
}

/// Kept lights.
#[derive(Debug)]
pub(crate) struct Resident {
    /// The read-back VPLs they stand for; `None` where none were read back ([`Held`]).
    key: Option<Key>,
    lights: Option<Detached>,
    held: Option<Held>,
}

/// The bounds (lo, hi) of kept VPLs, or the index of the first invalid one.
pub(crate) type Bounds = Result<(Vec3, Vec3), usize>;

/// What is kept of VPLs that were not read back.
#[derive(Debug)]
pub(crate) struct Held {
    /// Their number.
    pub(crate) count: usize,
    /// The parts the kept lights are in, one after the other: all of them, or one per
    /// normal bin.
    parts: Vec<Part>,
    /// The factor of their fluxes (one over the number of light paths).
    pub(crate) scale: f32,
    /// The VPLs as the light-path kernel wrote them (48 bytes each, flux not yet scaled).
    records: Option<Detached>,
}

/// A part of kept VPLs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Part {
    /// Its first VPL among the kept lights.
    pub(crate) first: usize,
    /// How many.
    pub(crate) count: usize,
    /// Their bounds (lo, hi), or the index of the first invalid one within the part (as
    /// [`lighting_grid::bounds`](lgh_core::lighting_grid::bounds) finds them).
    pub(crate) bounds: Bounds,
}

/// The kept VPLs of each thread that renders a frame (a frame makes its VPLs and builds
/// its hierarchies on one thread, and frames may run on several threads at once).
#[derive(Debug, Default)]
pub(crate) struct Slots(Mutex<Vec<(ThreadId, Resident)>>);

/// The most threads whose VPLs are kept at once (the oldest go first).
const MAX_SLOTS: usize = 8;

impl Slots {
    /// Runs `f` on this thread's slot.
    fn with<T>(&self, f: impl FnOnce(&mut Option<Resident>) -> T) -> T {
        let mut all = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        let me = std::thread::current().id();
        let at = all.iter().position(|(t, _)| *t == me);
        let mut mine = at.map(|i| all.remove(i).1);
        let out = f(&mut mine);
        if let Some(r) = mine {
            if all.len() >= MAX_SLOTS {
                all.remove(0);
            }
            all.push((me, r));
        }
        out
    }
}

/// Keeps `lights` (the build's layout) for the VPLs of `key`.
pub(crate) fn keep(ctx: &GpuContext, key: Key, lights: Lease<'_>) {
    let r = Resident {
        key: Some(key),
        lights: Some(lights.detach()),
        held: None,
    };
    ctx.resident_vpls().with(|slot| *slot = Some(r));
}

/// Keeps `lights` (the build's layout) and `records` (the light-path kernel's) of VPLs that
/// were not read back, with what `held` says of them.
pub(crate) fn keep_held(ctx: &GpuContext, lights: Lease<'_>, records: Lease<'_>, mut held: Held) {
    held.records = Some(records.detach());
    let r = Resident {
        key: None,
        lights: Some(lights.detach()),
        held: Some(held),
    };
    ctx.resident_vpls().with(|slot| *slot = Some(r));
}

impl Held {
    /// What is known of `count` VPLs not read back, kept in `parts`, their flux scaled
    /// by `scale`.
    pub(crate) fn new(count: usize, parts: Vec<Part>, scale: f32) -> Self {
        Self {
            count,
            parts,
            scale,
            records: None,
        }
    }
}

/// Drops this thread's kept lights, if any.
pub(crate) fn clear(ctx: &GpuContext) {
    ctx.resident_vpls().with(|slot| *slot = None);
}

/// This thread's kept lights if they are `lights`; the kept ones are dropped either way.
pub(crate) fn take<'c>(ctx: &'c GpuContext, lights: &InputLights) -> Option<Lease<'c>> {
    let kept = ctx.resident_vpls().with(Option::take)?;
    (kept.key == Some(Key::of(lights)))
        .then_some(kept.lights)
        .flatten()
        .map(|l| ctx.attach(l))
}

/// This thread's kept lights of part `part` of VPLs that were not read back, if it has
/// `count` of them, with their bounds (or the first invalid one, [`Part::bounds`]); where
/// it has not, whatever else is kept is dropped (their records stay, for
/// [`take_records`]). A part of several is copied into a lease of its own (on the GPU, in
/// a submission of its own); the kept lights go back to the pool with the last part that
/// has any.
pub(crate) fn take_held(
    ctx: &GpuContext,
    part: usize,
    count: usize,
) -> Option<(Lease<'_>, Bounds)> {
    let (source, last, p, whole) = ctx.resident_vpls().with(|slot| {
        let p = slot.as_ref().and_then(|k| {
            let p = *k.held.as_ref()?.parts.get(part)?;
            (k.lights.is_some() && p.count == count).then_some(p)
        });
        let Some(p) = p else {
            *slot = None;
            return None;
        };
        let kept = slot.as_mut()?;
        let parts = &kept.held.as_ref()?.parts;
        let whole = parts.len() == 1;
        let source = kept.lights.as_ref()?.buffer().clone();
        let last = (whole || parts[part + 1..].iter().all(|q| q.count == 0))
            .then(|| kept.lights.take())
            .flatten();
        Some((source, last, p, whole))
    })?;
    if whole {
        return Some((ctx.attach(last?), p.bounds));
    }
    let bytes = crate::grid::LIGHT_BYTES;
    let own = ctx
        .lease(
            crate::grid::LIGHTS_IN,
            p.count as u64 * bytes,
            GpuContext::STORAGE,
        )
        .ok()?;
    let mut batch = crate::batch::Batch::new(ctx);
    batch.copy_buffer(
        &source,
        p.first as u64 * bytes,
        &own,
        0,
        p.count as u64 * bytes,
    );
    if let Some(d) = last {
        batch.keep(ctx.attach(d));
    }
    batch.submit();
    Some((own, p.bounds))
}

/// This thread's light-path records of `count` VPLs that were not read back, and their flux
/// scale, for a frame that reads them back after all; they are dropped from the slot.
pub(crate) fn take_records(ctx: &GpuContext, count: usize) -> Option<(Lease<'_>, f32)> {
    let (records, scale) = ctx.resident_vpls().with(|slot| {
        let held = slot.as_mut()?.held.as_mut().filter(|h| h.count == count)?;
        Some((held.records.take()?, held.scale))
    })?;
    Some((ctx.attach(records), scale))
}
