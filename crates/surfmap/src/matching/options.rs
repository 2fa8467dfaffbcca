//! Checked setters of [`MatchOptions`] for the values a user gives: `surfmap match`'s
//! `--beta`, `--position-weight`, `--search-candidates` and `--rim-tolerance`, and the
//! Python `match`'s `beta`, `position_weight`, `search_candidates` and `rim_tolerance`.
//! One check and one message for both; `name` is the argument as the caller spells it,
//! and the message starts with it.

use super::{MatchOptions, PositionWeight};

impl MatchOptions {
    /// The energy weights β `[bending, regularization, features]` (thesis 2.16): three,
    /// finite and ≥ 0.
    pub fn set_betas(&mut self, b: &[f64], name: &str) -> Result<(), String> {
        if b.len() != 3 {
            return Err(format!(
                "{name} takes three weights B,R,F (bending, regularization, features; default 1,0.01,5), got {}",
                b.len()
            ));
        }
        if b.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(format!("{name}: weights must be finite and ≥ 0, got {b:?}"));
        }
        (self.betas.bend, self.betas.reg, self.betas.features) = (b[0], b[1], b[2]);
        Ok(())
    }

    /// A fixed weight of the position term ([`PositionWeight::Fixed`]; 0: the thesis
    /// energy alone), finite and ≥ 0.
    pub fn set_position_weight(&mut self, w: f64, name: &str) -> Result<(), String> {
        if !w.is_finite() || w < 0.0 {
            return Err(format!("{name} must be finite and ≥ 0, got {w}"));
        }
        self.betas.position = w;
        self.position_weight = PositionWeight::Fixed;
        Ok(())
    }

    /// The outer-rim tolerance of rim completion
    /// ([`super::complete::Tolerance::elsewhere`], in mean edges of the vertex): finite
    /// and ≥ 0 (0 matches no vertex whose prediction misses B's outer rim).
    pub fn set_rim_tolerance(&mut self, edges: f64, name: &str) -> Result<(), String> {
        if !edges.is_finite() || edges < 0.0 {
            return Err(format!(
                "{name} must be a finite number of edges ≥ 0 (default {}), got {edges}",
                super::complete::COMPLETE_TOLERANCE.elsewhere
            ));
        }
        self.complete_tolerance.elsewhere = edges;
        Ok(())
    }

    /// The position term's relief width σ (ω units, [`super::solve::POSITION_RELIEF`]):
    /// finite, in `[0, 1]`; 0 turns it off.
    pub fn set_position_relief(&mut self, width: f64, name: &str) -> Result<(), String> {
        if !width.is_finite() || !(0.0..=1.0).contains(&width) {
            return Err(format!(
                "{name} must be a width in [0, 1] of the parameter square (0: off; {} is \
                 what BENCHMARKS.md measured), got {width}",
                super::solve::POSITION_RELIEF
            ));
        }
        self.position_relief = width;
        Ok(())
    }

    /// The similarity search's extra starts `[DEG, SCALE]`: rotated by ±DEG degrees and
    /// scaled by (1 ± SCALE); degrees ≥ 0, the scale step in [0, 1).
    pub fn set_search_candidates(&mut self, c: &[f64], name: &str) -> Result<(), String> {
        if c.len() != 2 || c.iter().any(|x| !x.is_finite() || *x < 0.0) || c[1] >= 1.0 {
            return Err(format!(
                "{name} takes DEG,SCALE: degrees ≥ 0 and a scale step in [0, 1), got {c:?}"
            ));
        }
        self.similarity_search.candidate_angle = c[0].to_radians();
        self.similarity_search.candidate_log_scale = (1.0 + c[1]).ln();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refused_value_leaves_the_options_as_they_were_and_names_the_argument() {
        let mut o = MatchOptions::default();
        let before = (
            o.betas.bend,
            o.betas.reg,
            o.betas.features,
            o.betas.position,
        );
        for bad in [&[1.0, 2.0][..], &[1.0, -1.0, 5.0], &[1.0, f64::NAN, 5.0]] {
            let e = o.set_betas(bad, "--beta").unwrap_err();
            assert!(e.starts_with("--beta"), "{e}");
        }
        for bad in [-1.0, f64::INFINITY] {
            assert!(
                o.set_position_weight(bad, "w")
                    .unwrap_err()
                    .starts_with("w ")
            );
        }
        for bad in [&[5.0][..], &[5.0, 1.0], &[-5.0, 0.1]] {
            assert!(o.set_search_candidates(bad, "c").is_err());
        }
        for bad in [-0.1, f64::NAN] {
            assert!(o.set_rim_tolerance(bad, "r").unwrap_err().starts_with("r "));
        }
        assert_eq!(
            o.complete_tolerance,
            MatchOptions::default().complete_tolerance
        );
        let after = (
            o.betas.bend,
            o.betas.reg,
            o.betas.features,
            o.betas.position,
        );
        assert_eq!(format!("{before:?}"), format!("{after:?}"));
        assert_eq!(o.position_weight, MatchOptions::default().position_weight);
    }

    #[test]
    fn accepted_values_are_set_in_the_solver_s_units() {
        let mut o = MatchOptions::default();
        o.set_betas(&[2.0, 0.02, 3.0], "beta").unwrap();
        assert_eq!(
            (o.betas.bend, o.betas.reg, o.betas.features),
            (2.0, 0.02, 3.0)
        );
        o.set_position_weight(0.0, "w").unwrap();
        assert_eq!(
            (o.betas.position, o.position_weight),
            (0.0, PositionWeight::Fixed)
        );
        o.set_search_candidates(&[90.0, 0.1], "c").unwrap();
        let s = &o.similarity_search;
        assert!((s.candidate_angle - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((s.candidate_log_scale.exp() - 1.1).abs() < 1e-15);
        o.set_rim_tolerance(3.0, "r").unwrap();
        assert_eq!(o.complete_tolerance.elsewhere, 3.0);
        assert_eq!(
            o.complete_tolerance.interior,
            MatchOptions::default().complete_tolerance.interior
        );
    }
}
