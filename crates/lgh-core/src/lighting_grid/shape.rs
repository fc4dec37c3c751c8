//! The shape of a lighting grid hierarchy without its lights: what a caller needs of a
//! hierarchy that a builder keeps on its device (a GPU's, which makes from it there what the
//! frame's later passes read): the geometry and where each level's lights start.

use super::LightingGrid;
use super::geometry::GridGeometry;

/// A [`LightingGrid`]'s geometry and level ranges, without its lights.
#[derive(Clone, Debug, PartialEq)]
pub struct GridShape {
    /// Grid geometry (origin, h_top, l_max).
    pub geometry: GridGeometry,
    /// `level_start[l - 1]..level_start[l]` are the lights of level l (l_max + 1 entries),
    /// as [`LightingGrid::level_start`].
    pub level_start: Vec<u32>,
}

impl GridShape {
    /// The top level l_max.
    #[must_use]
    pub fn l_max(&self) -> u32 {
        self.geometry.l_max
    }

    /// Index range of the lights of level `l` (1..=l_max).
    #[must_use]
    pub fn level_range(&self, l: u32) -> std::ops::Range<usize> {
        level_range(&self.level_start, l)
    }

    /// Total number of grid lights.
    #[must_use]
    pub fn len(&self) -> usize {
        self.level_start.last().map_or(0, |&n| n as usize)
    }

    /// True if there is no grid light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Index range of the lights of level `l` (1..=l_max) of a grid whose levels start at
/// `level_start` ([`LightingGrid::level_start`]).
pub(super) fn level_range(level_start: &[u32], l: u32) -> std::ops::Range<usize> {
    level_start[l as usize - 1] as usize..level_start[l as usize] as usize
}

impl LightingGrid {
    /// Its shape: geometry and level ranges.
    #[must_use]
    pub fn shape(&self) -> GridShape {
        GridShape {
            geometry: self.geometry,
            level_start: self.level_start.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::lighting_grid::{Construction, InputLights, LevelCount};

    /// A grid's shape has its length, levels and level ranges.
    #[test]
    fn a_shape_has_the_grids_levels() {
        let p: Vec<Vec3> = (0..200)
            .map(|i| Vec3::new((i % 7) as f32, (i % 11) as f32 * 0.5, (i % 13) as f32))
            .collect();
        let i = vec![Vec3::ONE; p.len()];
        let n = vec![Vec3::Y; p.len()];
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: Some(&n),
        };
        let (grid, _) =
            LightingGrid::build(&input, LevelCount::Auto, Construction::Restrict).expect("grid");
        let shape = grid.shape();
        assert!(grid.l_max() >= 2);
        assert_eq!(shape.len(), grid.len());
        assert_eq!(shape.l_max(), grid.l_max());
        for l in 1..=grid.l_max() {
            assert_eq!(shape.level_range(l), grid.level_range(l));
        }
    }
}
