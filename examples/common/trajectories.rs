//! Reading a pedestrian trajectory file as `ta_map` and `flow_map` do.

use std::path::Path;

use haunts::occupancy::bounds::{BoundsRule, RowCounts};
use haunts::tracking::{
    DelimitedOptions, EthOptions, Parsed, Trajectory, keep_near, read_delimited, read_eth,
};

type Error = Box<dyn std::error::Error>;

/// The trajectory file formats.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Format {
    /// An ETH/OpenTraj `obsmat.txt`.
    Eth,
    /// Whitespace columns `time id x y`.
    Txy,
}

impl Format {
    /// `eth` or `txy`.
    pub fn parse(name: &str) -> Result<Self, Error> {
        match name {
            "eth" => Ok(Self::Eth),
            "txy" => Ok(Self::Txy),
            other => Err(format!("unknown format `{other}`: eth or txy").into()),
        }
    }
}

/// The trajectories of the file: malformed lines skipped and counted, then samples far from
/// the bulk of all samples (or not finite) removed by the bounds rule, each reported on
/// standard error. Returns them with the samples skipped by reason.
pub fn read(path: &Path, format: Format) -> Result<(Parsed<Trajectory>, RowCounts), Error> {
    let mut parsed = match format {
        Format::Eth => read_eth(path, &EthOptions::default())?,
        Format::Txy => read_delimited(path, &DelimitedOptions::default())?,
    };
    super::report_malformed(path, &parsed);
    let kept = keep_near(std::mem::take(&mut parsed.records), &BoundsRule::default())?;
    for line in kept.skipped.describe(|i| format!("sample {i}")) {
        eprintln!("{}: {line}", path.display());
    }
    let mut rows = kept.skipped.counts;
    rows.non_finite += parsed.non_finite;
    parsed.records = kept.rows;
    Ok((parsed, rows))
}
