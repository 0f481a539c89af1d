//! Least-squares fits of planes and lines to point sets, by the principal
//! axes of the scatter matrix (centred, so millimetre-scale coordinates at
//! a metre's distance keep their precision).

use nalgebra::{Matrix3, SymmetricEigen};

use super::Vec3;

/// A plane `n·p = offset` with unit normal `n`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub normal: Vec3,
    pub offset: f64,
}

impl Plane {
    /// Signed distance of `p` from the plane, positive along the normal.
    #[inline]
    pub fn signed_distance(&self, p: &Vec3) -> f64 {
        self.normal.dot(p) - self.offset
    }

    /// The plane with its normal pointing away from the camera (`n·z > 0`),
    /// so "along the normal" always means "into the workpiece" (Eq. 34).
    pub fn facing_away_from_camera(self) -> Plane {
        if self.normal.z < 0.0 { Plane { normal: -self.normal, offset: -self.offset } } else { self }
    }

    /// Projects `p` onto the plane.
    pub fn project(&self, p: &Vec3) -> Vec3 {
        p - self.normal * self.signed_distance(p)
    }
}

/// Accumulates first and second moments for principal-axis fits.
#[derive(Debug, Clone, Copy, Default)]
pub struct Moments {
    count: usize,
    origin: Option<Vec3>,
    sum: Vec3,
    sum_sq: Matrix3<f64>,
}

impl Moments {
    /// Adds a point. The first point becomes the origin of the sums so
    /// large absolute coordinates do not cancel catastrophically.
    pub fn add(&mut self, p: &Vec3) {
        let o = *self.origin.get_or_insert(*p);
        let d = p - o;
        self.count += 1;
        self.sum += d;
        self.sum_sq += d * d.transpose();
    }

    pub fn count(&self) -> usize {
        self.count
    }

    /// The centroid, if any point was added.
    pub fn centroid(&self) -> Option<Vec3> {
        let o = self.origin?;
        Some(o + self.sum / self.count as f64)
    }

    /// Eigen-decomposition of the covariance: eigenvalues ascending with
    /// their unit eigenvectors.
    fn principal_axes(&self) -> Option<([f64; 3], [Vec3; 3])> {
        if self.count < 2 {
            return None;
        }
        let n = self.count as f64;
        let mean = self.sum / n;
        let cov = self.sum_sq / n - mean * mean.transpose();
        let eig = SymmetricEigen::new(cov);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let values = order.map(|i| eig.eigenvalues[i]);
        let vectors = order.map(|i| eig.eigenvectors.column(i).into_owned());
        Some((values, vectors))
    }

    /// The least-squares plane, if at least three points span one.
    pub fn plane(&self) -> Option<Plane> {
        if self.count < 3 {
            return None;
        }
        let (values, vectors) = self.principal_axes()?;
        if values[1] <= 0.0 {
            return None;
        }
        let normal = vectors[0].normalize();
        let centroid = self.centroid()?;
        Some(Plane { normal, offset: normal.dot(&centroid) }.facing_away_from_camera())
    }

    /// How the points spread in their plane: the unit direction they
    /// spread along most, and how many times further along it than across
    /// it (the ratio of the two largest standard deviations). None for
    /// fewer than two distinct points.
    pub fn elongation(&self) -> Option<(Vec3, f64)> {
        let (values, vectors) = self.principal_axes()?;
        if values[2] <= 0.0 {
            return None;
        }
        let ratio = (values[2] / values[1].max(f64::MIN_POSITIVE)).sqrt();
        Some((vectors[2].normalize(), ratio))
    }

    /// The least-squares line as (point on it, unit direction).
    pub fn line(&self) -> Option<(Vec3, Vec3)> {
        let (values, vectors) = self.principal_axes()?;
        if values[2] <= 0.0 {
            return None;
        }
        Some((self.centroid()?, vectors[2].normalize()))
    }
}

impl<'a> FromIterator<&'a Vec3> for Moments {
    fn from_iter<I: IntoIterator<Item = &'a Vec3>>(iter: I) -> Self {
        let mut m = Moments::default();
        for p in iter {
            m.add(p);
        }
        m
    }
}

/// Points made on the fly (read from a cloud by index and converted from
/// its `f32`, say) are summed a block at a time, with no vector of them
/// all in between: each block is read in full before any of it is summed,
/// so the reads overlap rather than wait on the sums (summed as they
/// came, the sampled points of a raw frame's plates took 0.6 ms more to
/// fit than read into a vector first).
impl FromIterator<Vec3> for Moments {
    fn from_iter<I: IntoIterator<Item = Vec3>>(iter: I) -> Self {
        const BLOCK: usize = 256;
        let mut m = Moments::default();
        let mut points = iter.into_iter();
        let mut block = [Vec3::zeros(); BLOCK];
        loop {
            // `zip` asks the block for a slot first, so no point is taken
            // from `points` that the block has no room for.
            let read = block.iter_mut().zip(&mut points).map(|(slot, p)| *slot = p).count();
            block[..read].iter().for_each(|p| m.add(p));
            if read < BLOCK {
                return m;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_fit_recovers_a_tilted_plane_far_from_the_origin() {
        let n = Vec3::new(0.3, -0.2, 1.0).normalize();
        let [u, v] = crate::geometry::plane_axes(&n).unwrap();
        let origin = Vec3::new(120.0, -40.0, 950.0);
        let pts: Vec<Vec3> =
            (0..400).map(|i| origin + u * ((i % 20) as f64 * 3.0) + v * ((i / 20) as f64 * 2.0)).collect();
        let plane = pts.iter().collect::<Moments>().plane().unwrap();
        assert!((plane.normal - n).norm() < 1e-9);
        assert!(plane.signed_distance(&origin).abs() < 1e-9);
        assert!(plane.normal.z > 0.0);
    }

    #[test]
    fn points_summed_a_block_at_a_time_give_the_moments_of_the_same_points_borrowed() {
        // Several blocks of the owned form's, the last one part full.
        let pts: Vec<Vec3> =
            (0..700).map(|i| Vec3::new(i as f64 * 0.7, (i % 13) as f64, 900.0 + (i % 7) as f64)).collect();
        let borrowed: Moments = pts.iter().collect();
        let owned: Moments = pts.iter().copied().collect();
        assert_eq!(owned.count(), borrowed.count());
        assert_eq!(owned.centroid(), borrowed.centroid());
        assert_eq!(owned.plane().map(|p| (p.normal, p.offset)), borrowed.plane().map(|p| (p.normal, p.offset)));
    }

    #[test]
    fn line_fit_recovers_direction() {
        let d = Vec3::new(1.0, 0.1, -0.2).normalize();
        let pts: Vec<Vec3> = (0..50).map(|i| Vec3::new(5.0, 6.0, 700.0) + d * i as f64).collect();
        let (c, dir) = pts.iter().collect::<Moments>().line().unwrap();
        assert!(dir.cross(&d).norm() < 1e-9);
        assert!((c - Vec3::new(5.0, 6.0, 700.0) - d * 24.5).norm() < 1e-9);
    }

    #[test]
    fn elongation_is_the_long_side_over_the_short_one() {
        // A uniform 60 x 10 grid: standard deviations in the ratio 6.
        let pts: Vec<Vec3> = (0..600).map(|i| Vec3::new((i % 60) as f64 + 0.5, (i / 60) as f64 + 0.5, 500.0)).collect();
        let (dir, ratio) = pts.iter().collect::<Moments>().elongation().unwrap();
        assert!(dir.cross(&Vec3::x()).norm() < 1e-9);
        assert!((ratio - 6.0).abs() < 0.05, "{ratio}");
    }

    #[test]
    fn degenerate_sets_give_none() {
        assert!(Moments::default().plane().is_none());
        let line: Vec<Vec3> = (0..10).map(|i| Vec3::new(i as f64, 0.0, 1.0)).collect();
        assert!(line.iter().collect::<Moments>().plane().is_none());
    }
}
