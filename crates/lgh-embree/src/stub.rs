//! The scene of a build without Embree: it cannot be made.

use crate::{BuildQuality, Error, Hit, HitFilter, Ray};

/// A committed triangle scene (this build has no Embree: [`Scene::new`] always fails).
#[derive(Debug)]
pub struct Scene {
    _never: std::convert::Infallible,
}

impl Scene {
    /// Fails with [`Error::NotBuilt`] (after the same checks of the mesh as with Embree).
    ///
    /// # Errors
    /// Always.
    pub fn new(
        vertices: &[[f32; 3]],
        triangles: &[[u32; 3]],
        _quality: BuildQuality,
    ) -> Result<Self, Error> {
        crate::check_mesh(vertices, triangles)?;
        Err(Error::NotBuilt)
    }

    /// Fails with [`Error::NotBuilt`], as [`Scene::new`].
    ///
    /// # Errors
    /// Always.
    pub fn with_filter(
        vertices: &[[f32; 3]],
        triangles: &[[u32; 3]],
        quality: BuildQuality,
        _filter: Option<HitFilter>,
    ) -> Result<Self, Error> {
        Self::new(vertices, triangles, quality)
    }

    /// Never called: no scene exists.
    #[must_use]
    pub fn intersect(&self, _ray: &Ray) -> Option<Hit> {
        match self._never {}
    }

    /// Never called: no scene exists.
    #[must_use]
    pub fn occluded(&self, _ray: &Ray) -> bool {
        match self._never {}
    }

    /// Never called: no scene exists.
    pub fn occluded_many(&self, _rays: &[Ray], _coherent: bool, _out: &mut [bool]) {
        match self._never {}
    }

    /// Never called: no scene exists.
    pub fn intersect_many(&self, _rays: &[Ray], _coherent: bool, _out: &mut [Option<Hit>]) {
        match self._never {}
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_build_without_embree_says_so() {
        let r = super::Scene::new(&[[0.0; 3]; 3], &[[0, 1, 2]], crate::BuildQuality::Low);
        assert_eq!(r.err(), Some(crate::Error::NotBuilt));
        const { assert!(!crate::AVAILABLE) };
    }
}
