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

use std::sync::PoisonError;

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
    key: Key,
    lights: Detached,
}

/// Keeps `lights` (the build's layout) for the VPLs of `key`.
pub(crate) fn keep(ctx: &GpuContext, key: Key, lights: Lease<'_>) {
    *slot(ctx) = Some(Resident {
        key,
        lights: lights.detach(),
    });
}

/// Drops the kept lights, if any.
pub(crate) fn clear(ctx: &GpuContext) {
    *slot(ctx) = None;
}

/// The kept lights if they are `lights`; the kept ones are dropped either way.
pub(crate) fn take<'c>(ctx: &'c GpuContext, lights: &InputLights) -> Option<Lease<'c>> {
    let kept = slot(ctx).take()?;
    (kept.key == Key::of(lights)).then(|| ctx.attach(kept.lights))
}

fn slot(ctx: &GpuContext) -> std::sync::MutexGuard<'_, Option<Resident>> {
    ctx.resident_vpls()
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
}
