//! Mass, centre of mass and principal inertia of the solid parts, from their shapes.
//!
//! Every part of the model is a uniform box or a uniform rod whose axes are those of its
//! frame, and the parts of one link are stacked along its z axis, so each link's inertia
//! tensor stays diagonal in its frame (checked by [`Inertial::combine`]'s callers' shapes,
//! documented in `docs/twin.md`). Computed in f64.

/// Mass properties of one rigid part, in the frame of its body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass, m.
    pub com_m: [f64; 3],
    /// Diagonal of the inertia tensor about the centre of mass, along the frame's axes, kg·m².
    pub diag_kg_m2: [f64; 3],
}

impl Inertial {
    /// A uniform box of size `size_m` (full lengths along x, y, z) centred at `center_m`.
    pub fn solid_box(mass_kg: f32, size_m: [f32; 3], center_m: [f32; 3]) -> Inertial {
        let m = f64::from(mass_kg);
        let [a, b, c] = size_m.map(f64::from);
        Inertial {
            mass_kg: m,
            com_m: center_m.map(f64::from),
            diag_kg_m2: [
                m * (b * b + c * c) / 12.0,
                m * (a * a + c * c) / 12.0,
                m * (a * a + b * b) / 12.0,
            ],
        }
    }

    /// A uniform solid cylinder of radius `radius_m` from the origin down to `−length_m` on z.
    pub fn rod_z(mass_kg: f32, length_m: f32, radius_m: f32) -> Inertial {
        let m = f64::from(mass_kg);
        let (l, r) = (f64::from(length_m), f64::from(radius_m));
        let across = m * (3.0 * r * r + l * l) / 12.0;
        Inertial {
            mass_kg: m,
            com_m: [0.0, 0.0, -0.5 * l],
            diag_kg_m2: [across, across, 0.5 * m * r * r],
        }
    }

    /// The two parts as one: total mass, common centre of mass, and the inertia about it by
    /// the parallel-axis theorem. Only the diagonal is kept, which is exact when the two
    /// centres differ along one axis only (the case of every link of this model).
    pub fn combine(&self, other: &Inertial) -> Inertial {
        let m = self.mass_kg + other.mass_kg;
        let com: [f64; 3] = core::array::from_fn(|i| {
            (self.mass_kg * self.com_m[i] + other.mass_kg * other.com_m[i]) / m
        });
        let shifted = |part: &Inertial| -> [f64; 3] {
            let d: [f64; 3] = core::array::from_fn(|i| part.com_m[i] - com[i]);
            [
                part.diag_kg_m2[0] + part.mass_kg * (d[1] * d[1] + d[2] * d[2]),
                part.diag_kg_m2[1] + part.mass_kg * (d[0] * d[0] + d[2] * d[2]),
                part.diag_kg_m2[2] + part.mass_kg * (d[0] * d[0] + d[1] * d[1]),
            ]
        };
        let (a, b) = (shifted(self), shifted(other));
        Inertial {
            mass_kg: m,
            com_m: com,
            diag_kg_m2: [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rod_about_its_end_is_ml2_over_3() {
        // A thin rod about its end: I = m·l²/3 = the inertia about the centre + m·(l/2)².
        let rod = Inertial::rod_z(0.3, 0.5, 1e-6);
        let about_end = rod.diag_kg_m2[0] + rod.mass_kg * 0.25 * 0.25;
        assert!((about_end - 0.3 * 0.25 / 3.0).abs() < 1e-9);
    }

    #[test]
    fn two_halves_make_the_whole_box() {
        let whole = Inertial::solid_box(2.0, [0.2, 0.1, 0.4], [0.0; 3]);
        let top = Inertial::solid_box(1.0, [0.2, 0.1, 0.2], [0.0, 0.0, 0.1]);
        let bottom = Inertial::solid_box(1.0, [0.2, 0.1, 0.2], [0.0, 0.0, -0.1]);
        let both = top.combine(&bottom);
        assert!((both.mass_kg - whole.mass_kg).abs() < 1e-12);
        for i in 0..3 {
            assert!(
                (both.diag_kg_m2[i] - whole.diag_kg_m2[i]).abs() < 1e-9,
                "{i}"
            );
            assert!(both.com_m[i].abs() < 1e-12);
        }
    }
}
