//! Options shared by several commands: the building, the kernel and the surveyor model.

use std::path::Path;

use clap::{Args as ClapArgs, ValueEnum};
use trailprint::building::Building;
use trailprint::gp::Kernel;
use trailprint::surveyor::{
    DEFAULT_ROBOT_INTERVAL_M, DEFAULT_ROBOT_SPEED_MPS, DEFAULT_SCAN_INTERVAL_S, DEFAULT_STEP_ERROR,
    DEFAULT_STEP_LENGTH_M, DEFAULT_TURN_THRESHOLD_DEG, DEFAULT_WALKING_SPEED_MPS, Surveyor,
};
use trailprint::{Error, Result};

/// Where the building comes from.
#[derive(ClapArgs, Debug, Clone)]
pub struct BuildingOpts {
    /// A `survey-building/1` JSON file, or the name (or id) of a building in the database.
    #[arg(long, value_name = "FILE|NAME")]
    pub building: String,
}

impl BuildingOpts {
    /// Loads the file, or the building of that name from the database `db`.
    pub fn load(&self, db: Option<&Path>) -> Result<Building> {
        crate::store_cli::load_building(&self.building, db)
    }
}

/// `--kernel SF2,ELL,SN2`.
#[derive(ClapArgs, Debug, Clone, Default)]
pub struct KernelOpts {
    /// Kernel hyperparameters; default: the file's `kernel`, else fitted on its pilot data.
    #[arg(long, value_name = "SF2,ELL,SN2", value_parser = parse_kernel)]
    pub kernel: Option<Kernel>,
}

/// Parses `SF2,ELL,SN2`.
pub fn parse_kernel(s: &str) -> std::result::Result<Kernel, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("expected SF2,ELL,SN2 (three numbers), got {s:?}"));
    }
    let mut v = [0.0; 3];
    for (i, (p, name)) in parts.iter().zip(["SF2", "ELL", "SN2"]).enumerate() {
        v[i] = p
            .parse::<f64>()
            .map_err(|_| format!("{name} is not a number: {p:?}"))?;
    }
    let k = Kernel::new(v[0], v[1], v[2]);
    k.validate("--kernel").map_err(|e| e.to_string())?;
    Ok(k)
}

impl KernelOpts {
    /// The kernel to use for `b`, a building outside the database's bookkeeping, and where
    /// it came from: the core's policy ([`trailprint::store::unstored_planning_kernel`]:
    /// option, file, fit). Planning a stored building goes through
    /// `Store::plan_and_save`, which also takes the building's latest stored fit.
    pub fn resolve(&self, b: &Building) -> Result<(Kernel, String)> {
        let k =
            trailprint::store::unstored_planning_kernel(b, self.kernel).map_err(|e| hint(e, b))?;
        Ok((k.kernel, k.source.to_string()))
    }
}

/// A fit error with what to type to fix it: for a building without pilot data, the
/// option or the command that adds some; for pilot data that cannot be fitted (no
/// access point heard at enough locations, no spatial variation), the option.
pub fn hint(e: Error, b: &Building) -> Error {
    match e {
        Error::Fit(m) if b.pilot.len() >= 3 => Error::Fit(format!(
            "{m} (on the command line: --kernel SF2,ELL,SN2, for example --kernel 40,6,9)"
        )),
        Error::Fit(_) if b.pilot.len() < 3 => Error::Fit(format!(
            "building {:?} has {} pilot fingerprint(s) and no kernel; give one with \
             --kernel SF2,ELL,SN2 (for example --kernel 40,6,9), or add pilot data (at \
             least 3 locations) with `trailprint pilot add {:?} PILOT.json`",
            b.name,
            b.pilot.len(),
            b.name
        )),
        other => other,
    }
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    Robot,
    Human,
}

/// The surveyor model options of SPEC section 4.
#[derive(ClapArgs, Debug, Clone)]
pub struct ModelOpts {
    /// Who walks: the paper's robot or a human with a step counter.
    #[arg(long, value_enum, default_value = "robot")]
    pub model: ModelKind,
    /// Robot: metres between samples (speed x scan period).
    #[arg(long, default_value_t = DEFAULT_ROBOT_INTERVAL_M)]
    pub interval: f64,
    /// Human: walking speed, m/s.
    #[arg(long, default_value_t = DEFAULT_WALKING_SPEED_MPS)]
    pub speed: f64,
    /// Human: seconds between completed Wi-Fi scans.
    #[arg(long, default_value_t = DEFAULT_SCAN_INTERVAL_S)]
    pub scan_interval: f64,
    /// Human: relative step-length error.
    #[arg(long, default_value_t = DEFAULT_STEP_ERROR)]
    pub step_error: f64,
    /// Human: a turn sharper than this many degrees is a check-in.
    #[arg(long, default_value_t = DEFAULT_TURN_THRESHOLD_DEG)]
    pub turn_threshold: f64,
}

impl ModelOpts {
    /// The surveyor these options describe, with the default step length and robot speed
    /// (the planner's utility depends on neither), validated.
    pub fn model(&self) -> Result<Surveyor> {
        self.surveyor(DEFAULT_STEP_LENGTH_M, DEFAULT_ROBOT_SPEED_MPS)
    }

    /// The surveyor these options describe, walking with `step_length_m` (a human) or
    /// driving at `robot_speed_mps` (a robot), validated.
    pub fn surveyor(&self, step_length_m: f64, robot_speed_mps: f64) -> Result<Surveyor> {
        let m = match self.model {
            ModelKind::Robot => Surveyor::Robot {
                interval_m: self.interval,
                speed_mps: robot_speed_mps,
            },
            ModelKind::Human => Surveyor::Human {
                step_length_m,
                speed_mps: self.speed,
                scan_interval_s: self.scan_interval,
                step_error: self.step_error,
                turn_threshold_deg: self.turn_threshold,
            },
        };
        m.validate()?;
        Ok(m)
    }
}

/// Splits a comma-separated walk.
pub fn split_walk(s: &str) -> Vec<String> {
    s.split(',')
        .map(|x| x.trim().to_string())
        .filter(|x| !x.is_empty())
        .collect()
}

/// Serialises to one line of JSON (plain data cannot fail to serialise).
pub fn json_line<T: serde::Serialize>(v: &T) -> Result<String> {
    serde_json::to_string(v).map_err(|e| Error::InvalidRequest(format!("JSON output: {e}")))
}

/// Parses a planner name for clap (`auto`, `greedy`, `genetic`, ...).
pub fn parse_algorithm(s: &str) -> std::result::Result<trailprint::plan::Algorithm, String> {
    trailprint::plan::Algorithm::from_name(s).map_err(|e| e.to_string())
}

/// `--time-limit SECONDS` as a duration; a negative or non-finite value is an error.
pub fn time_limit(seconds: Option<f64>) -> Result<Option<std::time::Duration>> {
    match seconds {
        None => Ok(None),
        Some(t) if t.is_finite() && t >= 0.0 => Ok(Some(std::time::Duration::from_secs_f64(t))),
        Some(t) => Err(Error::InvalidRequest(format!(
            "--time-limit must be a non-negative number of seconds, got {t}"
        ))),
    }
}

/// The plan settings `plan` and `team-plan` share: the surveyor model, the planner, its
/// seed and `--time-limit`; planner parameters and memory budget at their defaults.
pub fn plan_settings(
    model: &ModelOpts,
    memory: MemoryOpts,
    algorithm: trailprint::plan::Algorithm,
    seed: u64,
    time_limit_s: Option<f64>,
) -> Result<trailprint::plan::PlanSettings> {
    Ok(trailprint::plan::PlanSettings {
        model: model.model()?,
        algorithm,
        seed,
        time_limit: time_limit(time_limit_s)?,
        memory_budget: memory.bytes(),
        ..trailprint::plan::PlanSettings::default()
    })
}

/// How the walks of a command are evaluated: who walks, the kernel and the memory the
/// evaluation may take (every command that plans or evaluates walks).
#[derive(ClapArgs, Debug, Clone)]
pub struct EvalOpts {
    #[command(flatten)]
    pub model: ModelOpts,
    #[command(flatten)]
    pub kernel: KernelOpts,
    #[command(flatten)]
    pub memory: MemoryOpts,
}

/// The most memory a plan or an evaluation may use: the option of every command that
/// plans or evaluates walks, so that a refusal's advice to raise it can be followed there.
#[derive(ClapArgs, Debug, Clone, Copy)]
pub struct MemoryOpts {
    /// Most memory the plan (or evaluation) may use, MiB; a larger request is refused with
    /// the size it needs.
    #[arg(long, value_name = "MIB", default_value_t = 512)]
    pub memory_budget: u64,
}

impl MemoryOpts {
    /// The budget in bytes.
    pub fn bytes(self) -> u64 {
        self.memory_budget.saturating_mul(1 << 20)
    }
}

/// Where a walk starts and ends, and how long it may be.
#[derive(ClapArgs, Debug, Clone)]
pub struct RouteOpts {
    /// Start vertex id.
    #[arg(long)]
    pub start: String,
    /// End vertex id [default: the start, a walk back to where it began].
    #[arg(long)]
    pub end: Option<String>,
    /// Budget: the longest walk allowed, metres. (A negative value is read as a number,
    /// so that the planner can say that a budget must be positive.)
    #[arg(long, allow_negative_numbers = true)]
    pub budget: f64,
}

impl RouteOpts {
    /// The end vertex: `--end`, else the start (most surveys end where they began).
    pub fn end(&self) -> &str {
        self.end.as_deref().unwrap_or(&self.start)
    }
}
