//! Checked setters of [`MatchOptions`] for the values a user gives: `surfmap match`'s
//! `--beta`, `--position-weight` and `--search-candidates`, and the Python `match`'s
//! `beta`, `position_weight` and `search_candidates`. One check and one message for
//! both; `name` is the argument as the caller spells it, and the message starts with it.

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
