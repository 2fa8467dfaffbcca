//! After the report: a match whose verdict is not `ok` tries other starts before it is
//! reported (issue: "recover instead of reporting").
//!
//! The alternatives ([`super::align::alternatives`]) are the other distinct poses the
//! rigid alignment in space ended in, and the first start turned by a half or a quarter
//! turn. Each is solved on the coarsest level alone ([`super::solve::solve_coarsest`])
//! and scored by how much B's curvature there disagrees with A's
//! (`LevelEnergy::curvature_disagreement`, the measure the verdict reads; the first start
//! is scored the same way); the whole match is then made from the one that disagrees
//! least, when that is not the first, and kept when its verdict is better — or as good
//! with less disagreement. Matches whose verdict is `ok` pay nothing.

use serde::Serialize;

use super::MatchError;
use super::align::{self, Start};
use super::options::MatchOptions;
use super::post::{self, Correspondence};
use super::prepare::Prepared;
use super::report::confidence::Verdict;
use super::report::{self, MatchReport};
use super::solve::{self, Solved};

/// One run of the stages after the alignment: solve, post-process, report.
pub(crate) struct Attempt {
    pub start: Start,
    pub solved: Solved,
    pub correspondence: Correspondence,
    pub report: MatchReport,
}

impl Attempt {
    /// Solves from `start`, post-processes and reports (hole rims already paired for
    /// `start`: [`align::pair_holes`]).
    pub fn run(p: &Prepared<'_>, start: Start, options: &MatchOptions) -> Result<Self, MatchError> {
        let clock = std::time::Instant::now();
        let solved = solve::solve(&p.a, &p.b, start.clone(), options);
        let seconds_solve = clock.elapsed().as_secs_f64();
        let correspondence = post::post(p, &solved, options)?;
        let report = report::report(p, &solved, &correspondence, options, seconds_solve);
        Ok(Self {
            start,
            solved,
            correspondence,
            report,
        })
    }
}

/// What recovery did ([`super::Confidence::recovery`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Recovery {
    /// The verdict of the match from the first start.
    pub verdict_before: Verdict,
    /// The coarsest level's curvature disagreement from the first start.
    pub first: Option<f64>,
    /// Every alternative start tried: how it was found, and its coarsest level's
    /// curvature disagreement.
    pub tried: Vec<(String, Option<f64>)>,
    /// The alternative the whole match was made from (an index into `tried`), when one
    /// disagreed less than the first start on the coarsest level.
    pub solved_from: Option<usize>,
    /// Whether that match was kept (its verdict better than the first's, or as good
    /// with less disagreement).
    pub kept: bool,
    pub seconds: f64,
}

/// Recovery (module docs): `first` or a better attempt, its report saying what was tried.
pub(crate) fn recover(
    p: &mut Prepared<'_>,
    first: Attempt,
    options: &MatchOptions,
) -> Result<Attempt, MatchError> {
    let clock = std::time::Instant::now();
    let coarse = |p: &mut Prepared<'_>, mut start: Start| -> Result<Option<f64>, MatchError> {
        align::pair_holes(p, &mut start, options)?;
        let solved = solve::solve_coarsest(&p.a, &p.b, start, options);
        Ok(solve::curvature_disagreements(&p.a, &p.b, &solved, options).finest)
    };
    let candidates = align::alternatives(p, &first.start, options);
    let first_score = coarse(p, first.start.clone())?;
    let mut tried = vec![];
    for start in &candidates {
        tried.push((start.report.method.clone(), coarse(p, start.clone())?));
    }
    let best = (0..tried.len())
        .filter_map(|i| tried[i].1.map(|d| (i, d)))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .filter(|&(_, d)| first_score.is_none_or(|f| d < f))
        .map(|(i, _)| i);
    let mut recovery = Recovery {
        verdict_before: first.report.confidence.verdict,
        first: first_score,
        tried,
        solved_from: best,
        kept: false,
        seconds: 0.0,
    };
    let mut chosen = first;
    if let Some(i) = best {
        let mut start = candidates[i].clone();
        align::pair_holes(p, &mut start, options)?;
        let other = Attempt::run(p, start, options)?;
        if better(&other.report, &chosen.report) {
            recovery.kept = true;
            chosen = other;
        }
    }
    // The surfaces carry the hole rims of the start kept (the pictures read them).
    let mut start = chosen.start.clone();
    align::pair_holes(p, &mut start, options)?;
    recovery.seconds = clock.elapsed().as_secs_f64();
    chosen.report.confidence.recovery = Some(recovery);
    Ok(chosen)
}

/// Whether report `x`'s verdict is better than `y`'s, or as good with less curvature
/// disagreement.
fn better(x: &MatchReport, y: &MatchReport) -> bool {
    let (cx, cy) = (&x.confidence, &y.confidence);
    match cx.verdict.cmp(&cy.verdict) {
        std::cmp::Ordering::Less => true,
        std::cmp::Ordering::Greater => false,
        std::cmp::Ordering::Equal => match (
            cx.measures.curvature_disagreement,
            cy.measures.curvature_disagreement,
        ) {
            (Some(a), Some(b)) => a < b,
            _ => false,
        },
    }
}
