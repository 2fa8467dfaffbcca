//! The settings as front ends take them — a preset or α, an energy, a start, Newton's
//! numbers, each a name or a number — resolved into [`FlattenOptions`] in one place. The
//! command line's flags and the Python package's keywords both map onto
//! [`FlattenSettings`]; only the wording of [`SettingsError`] is theirs.

use super::options::{CoarseLevel, FlattenOptions, Multilevel, OptionError, Start};
use crate::energy::{Alpha, AlphaError, ContinuationNeedsLitke, Energy};
use crate::param::newton::NewtonSettings;

/// The α presets of Litke's energy (thesis (2.5)): the one table of their names and
/// weights ([`Alpha::conformal`] and its siblings say where each comes from).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Preset {
    /// α = (0.005, 0.005, 0.99): nearly conformal (angle-preserving).
    Conformal,
    /// α = (1/3, 1/3, 1/3): length, area and angle weighted equally.
    #[default]
    Balanced,
    /// α = (0.1, 0.8, 0.1): area-preserving emphasis.
    Area,
    /// α = (0.8, 0.1, 0.1): length-preserving emphasis.
    Length,
}

impl Preset {
    /// Every preset, in the order front ends list them.
    pub const ALL: [Preset; 4] = [
        Preset::Conformal,
        Preset::Balanced,
        Preset::Area,
        Preset::Length,
    ];

    /// The preset's weights.
    pub fn alpha(self) -> Alpha {
        match self {
            Preset::Conformal => Alpha::conformal(),
            Preset::Balanced => Alpha::balanced(),
            Preset::Area => Alpha::area(),
            Preset::Length => Alpha::length(),
        }
    }

    /// `conformal`, `balanced`, `area` or `length`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Conformal => "conformal",
            Preset::Balanced => "balanced",
            Preset::Area => "area",
            Preset::Length => "length",
        }
    }
}

/// The energy density a flattening minimizes, without its parameters ([`Energy`] with
/// them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EnergyKind {
    /// Litke's energy (thesis (2.5)) with the α of [`FlattenSettings`].
    #[default]
    Litke,
    /// Symmetric Dirichlet: σ1² + σ2² + σ1⁻² + σ2⁻² (as libigl SLIM minimizes).
    SymmetricDirichlet,
    /// MIPS: σ1/σ2 + σ2/σ1 (conformal; scale is free).
    Mips,
    /// As-rigid-as-possible: (σ1 − 1)² + (σ2 − 1)².
    Arap,
}

impl EnergyKind {
    /// Every energy, in the order front ends list them.
    pub const ALL: [EnergyKind; 4] = [
        EnergyKind::Litke,
        EnergyKind::SymmetricDirichlet,
        EnergyKind::Mips,
        EnergyKind::Arap,
    ];

    /// `litke`, `sd`, `mips` or `arap`.
    pub fn name(self) -> &'static str {
        match self {
            EnergyKind::Litke => "litke",
            EnergyKind::SymmetricDirichlet => "sd",
            EnergyKind::Mips => "mips",
            EnergyKind::Arap => "arap",
        }
    }
}

/// The initial map asked for ([`Start`] without its data).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StartKind {
    /// LSCM, or mean-value coordinates if LSCM flips a triangle; multilevel for large
    /// meshes ([`MultilevelKind`]).
    #[default]
    Auto,
    /// LSCM on the full mesh.
    Lscm,
    /// Mean-value coordinates onto a circle on the full mesh.
    MeanValue,
}

impl StartKind {
    /// Every start, in the order front ends list them.
    pub const ALL: [StartKind; 3] = [StartKind::Auto, StartKind::Lscm, StartKind::MeanValue];

    /// `auto`, `lscm` or `mean_value`.
    pub fn name(self) -> &'static str {
        match self {
            StartKind::Auto => "auto",
            StartKind::Lscm => "lscm",
            StartKind::MeanValue => "mean_value",
        }
    }
}

/// When the automatic start is multilevel ([`Multilevel`] without its data).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MultilevelKind {
    /// For meshes of 15k faces and more.
    #[default]
    Auto,
    /// For every mesh.
    On,
    /// Never.
    Off,
}

impl MultilevelKind {
    /// Every choice, in the order front ends list them.
    pub const ALL: [MultilevelKind; 3] = [
        MultilevelKind::Auto,
        MultilevelKind::On,
        MultilevelKind::Off,
    ];

    /// `auto`, `on` or `off`.
    pub fn name(self) -> &'static str {
        match self {
            MultilevelKind::Auto => "auto",
            MultilevelKind::On => "on",
            MultilevelKind::Off => "off",
        }
    }
}

/// The solver's settings as a command line or a keyword call gives them (the defaults
/// are the command line's: balanced, Litke's energy, automatic start, Newton's
/// defaults). [`Self::options`] resolves them.
#[derive(Clone, Debug, PartialEq)]
pub struct FlattenSettings {
    pub preset: Preset,
    /// α = (length, area, angle) weights (normalized to sum 1), overriding the preset.
    pub alpha: Option<[f64; 3]>,
    pub energy: EnergyKind,
    /// Continuation (§3.1.3): minimize first at this α, then move to the target in steps
    /// (Litke's energy only).
    pub from_alpha: Option<[f64; 3]>,
    pub start: StartKind,
    /// With [`StartKind::Auto`] only.
    pub multilevel: MultilevelKind,
    /// Vertices of the multilevel start's decimated copy (default: 1/20 of the mesh).
    pub coarse_vertices: Option<usize>,
    /// Newton iteration cap per continuation stage.
    pub max_iterations: usize,
    /// Stop when half the Newton decrement (energy per unit area) is below this.
    pub tolerance: f64,
    /// Armijo's sufficient-decrease constant.
    pub armijo_c: f64,
}

impl Default for FlattenSettings {
    fn default() -> Self {
        let newton = NewtonSettings::default();
        Self {
            preset: Preset::default(),
            alpha: None,
            energy: EnergyKind::default(),
            from_alpha: None,
            start: StartKind::default(),
            multilevel: MultilevelKind::default(),
            coarse_vertices: None,
            max_iterations: newton.max_iterations,
            tolerance: newton.tolerance,
            armijo_c: newton.armijo_c,
        }
    }
}

/// Settings that do not make options ([`FlattenSettings::options`]); the front ends word
/// each as their flag or keyword.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SettingsError {
    #[error("α: {0}")]
    Alpha(AlphaError),
    #[error("continuation start α: {0}")]
    FromAlpha(AlphaError),
    #[error(transparent)]
    Continuation(ContinuationNeedsLitke),
    #[error(
        "the multilevel start is an automatic start (an explicit start map is computed on the full mesh)"
    )]
    MultilevelNeedsAutoStart,
    #[error(transparent)]
    Option(OptionError),
}

impl FlattenSettings {
    /// The options these settings ask for, checked ([`FlattenOptions::validate`]): the
    /// energy (α from `alpha`, else the preset; continuation from `from_alpha`), the
    /// start and Newton's numbers; everything else at its default (holes filled,
    /// [`Cut::Auto`](crate::Cut::Auto), [`Bijective::WhenOverlapping`](super::Bijective)).
    pub fn options(&self) -> Result<FlattenOptions, SettingsError> {
        let target = match self.alpha {
            Some([l, a, c]) => Alpha::new(l, a, c).map_err(SettingsError::Alpha)?,
            None => self.preset.alpha(),
        };
        let mut energy = match self.energy {
            EnergyKind::Litke => Energy::litke(target),
            EnergyKind::SymmetricDirichlet => Energy::SymmetricDirichlet,
            EnergyKind::Mips => Energy::Mips,
            EnergyKind::Arap => Energy::Arap,
        };
        if let Some([l, a, c]) = self.from_alpha {
            let from = Alpha::new(l, a, c).map_err(SettingsError::FromAlpha)?;
            energy = energy
                .with_continuation(from)
                .map_err(SettingsError::Continuation)?;
        }
        let coarse = CoarseLevel {
            vertices: self.coarse_vertices,
            ..CoarseLevel::default()
        };
        let start = match (self.start, self.multilevel) {
            (StartKind::Auto, choice) => Start::Auto {
                multilevel: match choice {
                    MultilevelKind::Auto => Multilevel::Auto(coarse),
                    MultilevelKind::On => Multilevel::Always(coarse),
                    MultilevelKind::Off => Multilevel::Never,
                },
            },
            (_, MultilevelKind::On) => return Err(SettingsError::MultilevelNeedsAutoStart),
            (StartKind::Lscm, _) => Start::Lscm,
            (StartKind::MeanValue, _) => Start::MeanValue,
        };
        let mut options = FlattenOptions::new(energy).with_start(start);
        options.newton.max_iterations = self.max_iterations;
        options.newton.tolerance = self.tolerance;
        options.newton.armijo_c = self.armijo_c;
        options.validate().map_err(SettingsError::Option)?;
        Ok(options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default settings are the library's default options.
    #[test]
    fn default_settings_are_the_default_options() {
        assert_eq!(
            FlattenSettings::default().options().unwrap(),
            FlattenOptions::default()
        );
    }

    /// Each preset gives its α; an explicit α overrides it; names are distinct.
    #[test]
    fn presets_and_alpha() {
        for preset in Preset::ALL {
            let settings = FlattenSettings {
                preset,
                ..Default::default()
            };
            let options = settings.options().unwrap();
            assert_eq!(options.energy, Energy::litke(preset.alpha()));
            assert_eq!(
                Preset::ALL
                    .iter()
                    .filter(|p| p.name() == preset.name())
                    .count(),
                1
            );
        }
        assert_eq!(Preset::Conformal.alpha().alphas(), [0.005, 0.005, 0.99]);
        let given = FlattenSettings {
            preset: Preset::Area,
            alpha: Some([1.0, 1.0, 2.0]),
            ..Default::default()
        };
        assert_eq!(
            given.options().unwrap().energy,
            Energy::litke(Alpha::new(1.0, 1.0, 2.0).unwrap())
        );
    }

    /// Energies, continuation, starts and Newton's numbers reach the options; what
    /// cannot be combined is refused by name.
    #[test]
    fn settings_resolve_and_are_checked() {
        let sd = FlattenSettings {
            energy: EnergyKind::SymmetricDirichlet,
            ..Default::default()
        };
        assert_eq!(sd.options().unwrap().energy, Energy::SymmetricDirichlet);
        let continuation = FlattenSettings {
            from_alpha: Some([1.0, 1.0, 98.0]),
            preset: Preset::Length,
            ..Default::default()
        };
        assert_eq!(
            continuation.options().unwrap().energy,
            Energy::litke_from(Alpha::new(1.0, 1.0, 98.0).unwrap(), Alpha::length())
        );
        let bad = |s: FlattenSettings| s.options().unwrap_err();
        assert!(matches!(
            bad(FlattenSettings {
                from_alpha: Some([1.0; 3]),
                energy: EnergyKind::Mips,
                ..Default::default()
            }),
            SettingsError::Continuation(_)
        ));
        assert!(matches!(
            bad(FlattenSettings {
                alpha: Some([0.0, 1.0, 1.0]),
                ..Default::default()
            }),
            SettingsError::Alpha(AlphaError::LengthNotPositive(_))
        ));
        assert_eq!(
            bad(FlattenSettings {
                start: StartKind::Lscm,
                multilevel: MultilevelKind::On,
                ..Default::default()
            }),
            SettingsError::MultilevelNeedsAutoStart
        );
        assert_eq!(
            bad(FlattenSettings {
                tolerance: 0.0,
                ..Default::default()
            }),
            SettingsError::Option(OptionError::Tolerance(0.0))
        );
        let on = FlattenSettings {
            multilevel: MultilevelKind::On,
            coarse_vertices: Some(300),
            max_iterations: 7,
            ..Default::default()
        }
        .options()
        .unwrap();
        assert_eq!(
            on.start,
            Start::Auto {
                multilevel: Multilevel::Always(CoarseLevel::with_vertices(300))
            }
        );
        assert_eq!(on.newton.max_iterations, 7);
        let mean_value = FlattenSettings {
            start: StartKind::MeanValue,
            multilevel: MultilevelKind::Off,
            ..Default::default()
        };
        assert_eq!(mean_value.options().unwrap().start, Start::MeanValue);
    }
}
