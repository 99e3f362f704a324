//! How estimators and sensors see the world: closest-hit ray casting against a map
//! ([`RayCaster`]), the hit it returns ([`RayHit`]) and the surface [`Material`].
//!
//! The trait lives here, in the shared vocabulary, so that `fathom-sensors` and
//! `fathom-estimators` can cast rays without depending on the map crate
//! (`fathom-map` implements it on a triangle mesh). It is object safe
//! (`&dyn RayCaster`) and usable generically (`impl RayCaster`).
//!
//! Rules every implementation follows (and `fathom-map` tests against a brute-force
//! oracle):
//!
//! - A ray is `origin + t dir` with `t` in metres: the direction is normalized by the
//!   caster, so any finite non-zero direction is accepted.
//! - Invalid rays do not panic: a non-finite origin or direction, a zero direction,
//!   or a `max_range` that is NaN or `<= 0` gives `None`. `max_range = +inf` means
//!   "no limit".
//! - A hit counts when `MIN_RANGE < t <= max_range` ([`MIN_RANGE`] keeps a ray that
//!   starts on a surface from hitting that surface).
//! - The closest hit wins; ties at exactly equal range go to the lower triangle index.

use nalgebra::Vector3;

/// Hits at or below this range (m) are ignored: a ray that starts on a surface
/// (a beam leaving a wall, a receiver on a roof) does not hit that surface.
pub const MIN_RANGE: f64 = 1e-9;

/// The material of a surface: what a range sensor or a GNSS signal meets.
///
/// `Opaque` and `Glass` are the two the sensors model differently (glass: more range
/// noise, returns only near normal incidence); `Other(id)` keeps further materials
/// of a map apart (concrete, steel, ...) for the analysis, with the behaviour of
/// `Opaque` in the sensors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Material {
    /// An opaque, diffusely reflecting surface (concrete, stone, ground).
    Opaque,
    /// Glass: specular, weak diffuse return (facades, windows).
    Glass,
    /// Another material, identified by a number the map's material table assigns.
    Other(u16),
}

impl Material {
    /// Whether the surface is glass (the sensors' special case).
    pub fn is_glass(self) -> bool {
        matches!(self, Material::Glass)
    }
}

impl std::fmt::Display for Material {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Material::Opaque => write!(f, "opaque"),
            Material::Glass => write!(f, "glass"),
            Material::Other(id) => write!(f, "other({id})"),
        }
    }
}

/// One ray: origin and direction in the NED navigation frame, and the largest range
/// that counts as a hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point, NED, m.
    pub origin_in_nav: Vector3<f64>,
    /// Direction, NED (normalized by the caster; need not be unit).
    pub dir_in_nav: Vector3<f64>,
    /// Largest range counted as a hit, m (`+inf`: no limit).
    pub max_range: f64,
}

impl Ray {
    /// A ray from `origin_in_nav` along `dir_in_nav`, hits up to `max_range` m.
    pub fn new(origin_in_nav: Vector3<f64>, dir_in_nav: Vector3<f64>, max_range: f64) -> Self {
        Self {
            origin_in_nav,
            dir_in_nav,
            max_range,
        }
    }

    /// The unit direction, or `None` when the ray is invalid under the module's rules
    /// (non-finite origin or direction, zero direction, `max_range` NaN or `<= 0`).
    #[inline]
    pub fn unit_dir(&self) -> Option<Vector3<f64>> {
        let finite = self.origin_in_nav.iter().all(|c| c.is_finite())
            && self.dir_in_nav.iter().all(|c| c.is_finite());
        // false for NaN too
        let positive_range = self.max_range > 0.0;
        if !finite || !positive_range {
            return None;
        }
        let norm = self.dir_in_nav.norm();
        let usable = norm > 0.0 && norm.is_finite();
        if !usable {
            return None;
        }
        Some(self.dir_in_nav / norm)
    }
}

/// The closest hit of a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Range along the unit direction, m (`MIN_RANGE < range <= max_range`).
    pub range: f64,
    /// Index of the hit triangle in the map.
    pub triangle: u32,
    /// The hit triangle's material.
    pub material: Material,
    /// Unit normal of the hit triangle, NED, turned to face the ray
    /// (`normal_in_nav . dir <= 0`).
    pub normal_in_nav: Vector3<f64>,
}

impl RayHit {
    /// Incidence angle (rad, in `[0, pi/2]`) between the ray and the surface normal:
    /// 0 is head-on, pi/2 grazing. `unit_dir_in_nav` must be the ray's unit direction.
    pub fn incidence(&self, unit_dir_in_nav: &Vector3<f64>) -> f64 {
        let c = (-self.normal_in_nav.dot(unit_dir_in_nav)).clamp(0.0, 1.0);
        c.acos()
    }
}

/// The group size of [`RayCaster::cast_coherent`]: consecutive rays in groups of this
/// many are expected to be similar.
pub const COHERENT_GROUP: usize = 8;

/// A buffer of the wrong length was given to [`RayCaster::cast_batch`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cast_batch: {rays} rays but an output buffer of {hits} slots")]
pub struct BatchLengthMismatch {
    /// Number of rays given.
    pub rays: usize,
    /// Length of the output buffer.
    pub hits: usize,
}

impl BatchLengthMismatch {
    /// `Ok` when the output buffer has one slot per ray.
    ///
    /// # Errors
    /// The mismatch, when `hits.len() != rays.len()`.
    pub fn check(rays: &[Ray], hits: &[Option<RayHit>]) -> Result<(), Self> {
        if rays.len() == hits.len() {
            Ok(())
        } else {
            Err(Self {
                rays: rays.len(),
                hits: hits.len(),
            })
        }
    }
}

/// Closest-hit ray casting against a static map (see the module rules).
///
/// Implementations are read-only (`&self`) and use the calling thread only: the
/// Monte Carlo runner owns the threads, and one caster is shared by all of them (and
/// by the scoped threads of a grid or particle update), hence `Sync`.
pub trait RayCaster: Sync {
    /// The closest hit of the ray `origin_in_nav + t dir_in_nav`,
    /// `MIN_RANGE < t <= max_range`, or `None` (no hit, or an invalid ray).
    fn cast(
        &self,
        origin_in_nav: &Vector3<f64>,
        dir_in_nav: &Vector3<f64>,
        max_range: f64,
    ) -> Option<RayHit>;

    /// [`RayCaster::cast`] of a [`Ray`].
    fn cast_ray(&self, ray: &Ray) -> Option<RayHit> {
        self.cast(&ray.origin_in_nav, &ray.dir_in_nav, ray.max_range)
    }

    /// Casts every ray of `rays`, writing the closest hit of `rays[i]` into `hits[i]`
    /// (calling thread only; no allocation).
    ///
    /// # Errors
    /// [`BatchLengthMismatch`] when `hits.len() != rays.len()` (nothing is cast).
    fn cast_batch(
        &self,
        rays: &[Ray],
        hits: &mut [Option<RayHit>],
    ) -> Result<(), BatchLengthMismatch> {
        BatchLengthMismatch::check(rays, hits)?;
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = self.cast_ray(ray);
        }
        Ok(())
    }

    /// [`RayCaster::cast_batch`] for rays that come in runs of similar rays: each
    /// group of [`COHERENT_GROUP`] consecutive rays (`rays[8 m .. 8 m + 8]`) should have
    /// near origins and near directions (one beam from neighbouring grid points, say).
    /// The hits are those of `cast_batch`, bit for bit; a caster may cast such a group
    /// together (the BVH caster does), which is faster when the rays are coherent and
    /// slower when they are not. The default is `cast_batch`.
    ///
    /// # Errors
    /// [`BatchLengthMismatch`] when `hits.len() != rays.len()` (nothing is cast).
    fn cast_coherent(
        &self,
        rays: &[Ray],
        hits: &mut [Option<RayHit>],
    ) -> Result<(), BatchLengthMismatch> {
        self.cast_batch(rays, hits)
    }

    /// Whether the straight segment from `from_in_nav` to `to_in_nav` is free of the
    /// map (line of sight). A segment of zero length or with a non-finite end is
    /// reported as free only when both ends are equal and finite.
    fn line_of_sight(&self, from_in_nav: &Vector3<f64>, to_in_nav: &Vector3<f64>) -> bool {
        let d = to_in_nav - from_in_nav;
        let len = d.norm();
        if !len.is_finite() {
            return false;
        }
        if len <= MIN_RANGE {
            return true;
        }
        self.cast(from_in_nav, &d, len).is_none()
    }
}

impl<T: RayCaster + ?Sized> RayCaster for &T {
    fn cast(
        &self,
        origin_in_nav: &Vector3<f64>,
        dir_in_nav: &Vector3<f64>,
        max_range: f64,
    ) -> Option<RayHit> {
        (**self).cast(origin_in_nav, dir_in_nav, max_range)
    }

    fn cast_batch(
        &self,
        rays: &[Ray],
        hits: &mut [Option<RayHit>],
    ) -> Result<(), BatchLengthMismatch> {
        (**self).cast_batch(rays, hits)
    }

    fn cast_coherent(
        &self,
        rays: &[Ray],
        hits: &mut [Option<RayHit>],
    ) -> Result<(), BatchLengthMismatch> {
        (**self).cast_coherent(rays, hits)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plane `z = 5` (down = 5 m), opaque, triangle 0: a caster with no map crate.
    struct Floor;
    impl RayCaster for Floor {
        fn cast(&self, o: &Vector3<f64>, d: &Vector3<f64>, max_range: f64) -> Option<RayHit> {
            let d = Ray::new(*o, *d, max_range).unit_dir()?;
            let t = (5.0 - o.z) / d.z;
            (t > MIN_RANGE && t <= max_range).then_some(RayHit {
                range: t,
                triangle: 0,
                material: Material::Opaque,
                normal_in_nav: Vector3::new(0.0, 0.0, -d.z.signum()),
            })
        }
    }

    #[test]
    fn invalid_rays_give_none() {
        let o = Vector3::zeros();
        let down = Vector3::new(0.0, 0.0, 1.0);
        assert_eq!(Floor.cast(&o, &down, 10.0).unwrap().range, 5.0);
        assert!(Floor.cast(&o, &down, 4.0).is_none());
        assert!(Floor.cast(&o, &Vector3::zeros(), 10.0).is_none());
        assert!(Floor.cast(&o, &down, f64::NAN).is_none());
        assert!(Floor.cast(&o, &down, 0.0).is_none());
        assert!(Floor.cast(&o, &down, f64::INFINITY).is_some());
        let nan = Vector3::new(f64::NAN, 0.0, 0.0);
        assert!(Floor.cast(&nan, &down, 10.0).is_none());
        assert!(Floor.cast(&o, &nan, 10.0).is_none());
        // not unit: normalized
        assert_eq!(Floor.cast(&o, &(down * 3.0), 10.0).unwrap().range, 5.0);
    }

    #[test]
    fn batch_checks_lengths_and_matches_single_casts() {
        let caster: &dyn RayCaster = &Floor;
        let rays = [
            Ray::new(Vector3::zeros(), Vector3::new(0.0, 0.0, 1.0), 10.0),
            Ray::new(Vector3::zeros(), Vector3::new(0.0, 0.0, -1.0), 10.0),
            Ray::new(Vector3::zeros(), Vector3::new(1.0, 0.0, 1.0), 10.0),
        ];
        let mut hits = [None; 3];
        caster.cast_batch(&rays, &mut hits).unwrap();
        for (r, h) in rays.iter().zip(&hits) {
            assert_eq!(*h, caster.cast_ray(r));
        }
        assert!((hits[2].unwrap().range - 50f64.sqrt()).abs() < 1e-12);
        let mut short = [None; 2];
        assert_eq!(
            caster.cast_batch(&rays, &mut short),
            Err(BatchLengthMismatch { rays: 3, hits: 2 })
        );
    }

    #[test]
    fn line_of_sight_and_incidence() {
        let above = Vector3::new(0.0, 0.0, 0.0);
        assert!(!Floor.line_of_sight(&above, &Vector3::new(0.0, 0.0, 6.0)));
        assert!(Floor.line_of_sight(&above, &Vector3::new(0.0, 0.0, 4.0)));
        assert!(!Floor.line_of_sight(&above, &Vector3::new(f64::INFINITY, 0.0, 4.0)));
        let d = Vector3::new(1.0, 0.0, 1.0).normalize();
        let hit = Floor.cast(&above, &d, 100.0).unwrap();
        assert!((hit.incidence(&d) - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert_eq!(Material::Glass.to_string(), "glass");
        assert!(Material::Glass.is_glass() && !Material::Other(3).is_glass());
    }
}
