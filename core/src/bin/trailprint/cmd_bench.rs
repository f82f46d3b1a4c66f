//! `trailprint bench`: algorithms x budgets x seeds on given buildings; Markdown and CSV.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use clap::Args as ClapArgs;
use trailprint::building::Building;
use trailprint::gp::fit_kernel;
use trailprint::plan::bench::{BenchCase, BenchConfig, run_bench, summarise, to_csv, to_markdown};
use trailprint::plan::{Algorithm, Control, Params};
use trailprint::{Error, Result};

use crate::opts::{ModelOpts, parse_kernel};

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// An instance: `FILE:START:END:B1,B2,...` with an optional `:SF2,ELL,SN2` kernel
    /// (default: the file's kernel, else fitted on its pilot data). Repeatable.
    #[arg(long = "case", required = true)]
    cases: Vec<String>,
    /// Algorithms to run, comma-separated (default: all, the `coverage` baseline too).
    #[arg(
        long,
        default_value = "greedy,genetic,recursive-greedy,ero,exact,auto,coverage"
    )]
    algorithms: String,
    /// Seeds, comma-separated (deterministic algorithms run once with the first).
    #[arg(long, default_value = "1,2,3")]
    seeds: String,
    /// Time limit of one algorithm, `NAME=SECONDS` (repeatable; auto defaults to 2 s).
    #[arg(long = "time-limit", value_name = "ALG=SECONDS")]
    time_limits: Vec<String>,
    /// Genetic population size.
    #[arg(long, default_value_t = 200)]
    population: usize,
    /// Genetic generations.
    #[arg(long, default_value_t = 5)]
    generations: usize,
    /// Write the raw rows as CSV here.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write the summary tables as Markdown here (also printed).
    #[arg(long)]
    markdown: Option<PathBuf>,
    #[command(flatten)]
    model: ModelOpts,
}

fn bad(m: String) -> Error {
    Error::InvalidRequest(m)
}

/// A comma-separated list of numbers; `what` starts the message naming the one that is not.
fn numbers<T: std::str::FromStr>(list: &str, what: &str) -> Result<Vec<T>> {
    list.split(',')
        .map(|x| {
            x.trim()
                .parse::<T>()
                .map_err(|_| bad(format!("{what} {x:?} is not a number")))
        })
        .collect()
}

fn parse_case(s: &str) -> Result<BenchCase> {
    let parts: Vec<&str> = s.split(':').collect();
    if parts.len() != 4 && parts.len() != 5 {
        return Err(bad(format!(
            "--case {s:?}: expected FILE:START:END:BUDGETS[:SF2,ELL,SN2]"
        )));
    }
    let building = Arc::new(Building::load(&PathBuf::from(parts[0]))?);
    let budgets = numbers(parts[3], &format!("--case {s:?}: budget"))?;
    let kernel = match parts.get(4) {
        Some(k) => parse_kernel(k).map_err(bad)?,
        None => match building.kernel {
            Some(k) => k,
            None => {
                let f = fit_kernel(&building.pilot)?;
                eprintln!(
                    "{}: fitted kernel sf2={:.4} ell={:.4} sn2={:.4}",
                    building.name, f.kernel.sf2, f.kernel.ell, f.kernel.sn2
                );
                f.kernel
            }
        },
    };
    Ok(BenchCase {
        building,
        kernel,
        start: parts[1].to_string(),
        end: parts[2].to_string(),
        budgets,
    })
}

pub fn run(a: Args) -> Result<()> {
    let cases = a
        .cases
        .iter()
        .map(|c| parse_case(c))
        .collect::<Result<Vec<_>>>()?;
    let algorithms = a
        .algorithms
        .split(',')
        .map(|x| Algorithm::from_name(x.trim()))
        .collect::<Result<Vec<_>>>()?;
    let seeds = numbers(&a.seeds, "--seeds:")?;
    let mut time_limits = BTreeMap::new();
    for t in &a.time_limits {
        let (name, secs) = t
            .split_once('=')
            .ok_or_else(|| bad(format!("--time-limit {t:?}: expected ALG=SECONDS")))?;
        let alg = Algorithm::from_name(name.trim())?;
        let secs: f64 = secs
            .trim()
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite() && *x >= 0.0)
            .ok_or_else(|| bad(format!("--time-limit {t:?}: bad number of seconds")))?;
        time_limits.insert(alg.name().to_string(), Duration::from_secs_f64(secs));
    }
    let cfg = BenchConfig {
        algorithms,
        seeds,
        params: Params {
            population: a.population,
            generations: a.generations,
            ..Params::default()
        },
        model: a.model.model()?,
        time_limits,
    };
    let rows = run_bench(&cases, &cfg, &Control::new(), |r| {
        eprintln!(
            "{} B={} {} seed {}: {:.4} nats, {:.1} m, {} ms{}",
            r.building,
            r.budget,
            r.algorithm,
            r.seed,
            r.utility,
            r.length,
            r.elapsed_ms,
            match r.optimal {
                Some(true) => " (optimal)",
                Some(false) => " (not proved)",
                None => "",
            }
        );
    })?;
    let md = to_markdown(&summarise(&rows));
    println!("{md}");
    if let Some(p) = &a.csv {
        std::fs::write(p, to_csv(&rows)).map_err(|e| Error::io(p, e))?;
    }
    if let Some(p) = &a.markdown {
        std::fs::write(p, &md).map_err(|e| Error::io(p, e))?;
    }
    Ok(())
}
