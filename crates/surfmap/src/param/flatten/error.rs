//! Why a flattening failed: [`FlattenError`].

use super::options::OptionError;
use crate::linsolve::SolveError;
use crate::mesh::cut::CutError;
use crate::mesh::validate::{Defect, list_defects};
use crate::mesh::{IndexError, NotADisc};
use crate::param::InitialMapError;
use crate::param::element::RestTriangleError;

/// Why a flattening failed. The messages name the problem and the remedy in the
/// library's terms (options, `mesh::repair` functions).
#[derive(Debug, thiserror::Error)]
pub enum FlattenError {
    #[error(transparent)]
    Index(#[from] IndexError),
    #[error("the mesh cannot be flattened as a disc:\n{}", list_defects(.0))]
    NotADisc(Vec<Defect>),
    #[error("{0}; `repair::drop_degenerate` removes them")]
    Degenerate(#[from] RestTriangleError),
    #[error("invalid option: {0}")]
    Option(#[from] OptionError),
    #[error("linear solve failed: {0}")]
    Solve(#[from] SolveError),
    #[error("initial map: {0}")]
    InitialMap(#[from] InitialMapError),
    #[error("{}", no_start_message(*.lscm, *.mean_value, "`Cut::Auto` or `Cut::Along`"))]
    NoAdmissibleStart { lscm: usize, mean_value: usize },
    #[error("{}", no_start_after_cuts_message(*.cuts, *.lscm, *.mean_value, *.triangle, RUST_REMEDIES))]
    NoAdmissibleStartAfterCuts {
        /// Cuts along protrusions made ([`crate::param::protrusions`]).
        cuts: usize,
        /// Triangles each start flips or degenerates after them.
        lscm: usize,
        mean_value: usize,
        /// An input triangle the mean-value start flips, when it is one of the input's.
        triangle: Option<usize>,
    },
    #[error(
        "the LSCM start flips or degenerates {0} triangles; use `Start::Auto` (falls back to mean-value coordinates, injective by construction)"
    )]
    LscmFlipped(usize),
    #[error("the given initial map has {uvs} UVs, but the mesh has {vertices} vertices")]
    GivenStartLength { uvs: usize, vertices: usize },
    #[error(
        "the given initial map flips or degenerates {0} triangles; a start map must be injective"
    )]
    GivenStartFlipped(usize),
    #[error(
        "a given start map has no UVs for the {0} filled holes; fill them yourself (`repair::fill_holes`) and give UVs for the filled mesh, or use `Start::Auto`"
    )]
    GivenStartWithFilledHoles(usize),
    #[error(
        "a given start map has one UV per vertex, but the surface is cut open along seams ({0}); cut it yourself (`mesh::cut`) and give UVs for the opened mesh, or use `Start::Auto`"
    )]
    GivenStartWithCut(String),
    #[error(transparent)]
    Cut(#[from] CutError),
    #[error("internal error: the result has {0} flipped triangles; please report this mesh")]
    FlippedResult(usize),
    #[error("measuring the distortion for the distortion bound: {0}")]
    Distortion(#[from] crate::measure::MeasureError),
}

impl FlattenError {
    /// The message of [`FlattenError::NoAdmissibleStart`] or
    /// [`FlattenError::NoAdmissibleStartAfterCuts`] with a front end's words: `cutting` how
    /// to let the flattening cut, `remedies` its names for dropping degenerate triangles
    /// and for giving seams. `None` for every other error.
    pub fn no_start_worded(&self, cutting: &str, remedies: Remedies<'_>) -> Option<String> {
        match *self {
            FlattenError::NoAdmissibleStart { lscm, mean_value } => {
                Some(no_start_message(lscm, mean_value, cutting))
            }
            FlattenError::NoAdmissibleStartAfterCuts {
                cuts,
                lscm,
                mean_value,
                triangle,
            } => Some(no_start_after_cuts_message(
                cuts, lscm, mean_value, triangle, remedies,
            )),
            _ => None,
        }
    }
}

/// What [`FlattenError::NoAdmissibleStart`] says, `cutting` naming how to let the flattening
/// cut (the front ends word it as their flags or keywords).
fn no_start_message(lscm: usize, mean_value: usize, cutting: &str) -> String {
    format!(
        "both initial maps flipped triangles (LSCM: {lscm}, mean-value: {mean_value}); the mesh geometry is probably broken (non-finite or coincident vertices), or the surface has protrusions too long and thin for one chart, which only cutting along them can flatten ({cutting}; not with an explicit start)"
    )
}

/// How [`no_start_after_cuts_message`] names its remedies: dropping degenerate triangles,
/// and giving seams.
pub type Remedies<'a> = (&'a str, &'a str);

/// The library's names of the remedies.
const RUST_REMEDIES: Remedies<'static> = ("`repair::drop_degenerate`", "`Cut::Along`");

/// What [`FlattenError::NoAdmissibleStartAfterCuts`] says, its remedies named by
/// `remedies` (the front ends word them as their flags or keywords).
fn no_start_after_cuts_message(
    cuts: usize,
    lscm: usize,
    mean_value: usize,
    triangle: Option<usize>,
    (drop_degenerate, seams): Remedies<'_>,
) -> String {
    let cut = match cuts {
        0 => "with no protrusion left to cut along".to_string(),
        1 => "after 1 cut along a protrusion".to_string(),
        n => format!("after {n} cuts along protrusions"),
    };
    let at = triangle.map_or_else(String::new, |t| {
        format!(", triangle {t} (0-based) among them")
    });
    format!(
        "no initial map embeds the mesh {cut}: LSCM flips or degenerates {lscm} triangles and mean-value coordinates {mean_value}{at}. Mean-value coordinates flip only where triangles are too small or thin for floating point next to the rest of the chart: look for nearly coincident vertices and needle or sliver triangles there ({drop_degenerate}, remeshing), or give seams that open that region ({seams})"
    )
}

impl From<NotADisc> for FlattenError {
    fn from(e: NotADisc) -> Self {
        match e {
            NotADisc::Index(e) => FlattenError::Index(e),
            NotADisc::Defects(d) => FlattenError::NotADisc(d),
        }
    }
}
