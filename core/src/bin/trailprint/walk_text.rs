//! A walk as a person reads it: numbered steps with labels and floors, the time it takes,
//! and a printable turn-by-turn sheet whose sentences are the ones a live session shows
//! ([`trailprint::session::tracker::guidance_sentence`]).

use trailprint::building::Building;
use trailprint::samples::{Surveyor, check_in_flags};
use trailprint::session::tracker::{classify_turn, guidance_sentence};
use trailprint::session::types::Turn;

use crate::store_cli::{column_width, label_cell, printable};

/// The name a person uses for a floor: its name, else "floor N".
pub fn floor_name(b: &Building, floor: i64) -> String {
    b.floors
        .iter()
        .find(|f| f.id == floor)
        .and_then(|f| f.name.clone())
        .map_or_else(|| format!("floor {floor}"), |n| printable(&n))
}

/// `95 s` as "1 min 35 s", `4000 s` as "1 h 07 min".
pub fn duration_text(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    if s < 60 {
        format!("{s} s")
    } else if s < 3600 {
        format!("{} min {:02} s", s / 60, s % 60)
    } else {
        format!("{} h {:02} min", s / 3600, (s % 3600) / 60)
    }
}

/// Where the surveyor checks in along `walk` (SPEC section 4): the start, the end, every
/// turn sharper than the threshold and every change of floor (human); start and end only
/// for a robot, which needs none.
pub fn check_ins(b: &Building, walk: &[usize], model: &Surveyor) -> Vec<bool> {
    check_in_flags(b, walk, model.turn_threshold_deg())
}

/// Arc length from the start at each vertex of the walk, metres.
fn arcs(b: &Building, walk: &[usize]) -> Vec<f64> {
    let mut out = Vec::with_capacity(walk.len());
    let mut acc = 0.0;
    for (i, &v) in walk.iter().enumerate() {
        if i > 0
            && let Some(e) = b.edge_between(walk[i - 1], v)
        {
            acc += e.length;
        }
        out.push(acc);
    }
    out
}

/// The walk as a numbered table: step, vertex id, label, floor, metres from the start and
/// whether the surveyor checks in there.
pub fn steps_table(b: &Building, walk: &[usize], model: &Surveyor) -> Vec<String> {
    let arc = arcs(b, walk);
    let checks = check_ins(b, walk, model);
    let human = matches!(model, Surveyor::Human { .. });
    let id_w = column_width(walk.iter().map(|&v| printable(&b.vertices[v].id)), 6);
    let labels = walk.iter().map(|&v| {
        b.vertices[v]
            .label
            .as_deref()
            .map_or(String::new(), printable)
    });
    let label_w = column_width(labels, 5).min(28);
    let floors = b.floors.len() > 1;
    let mut lines = vec![format!(
        "  {:>4}  {:<id_w$}  {:<label_w$}  {}{:>8}{}",
        "step",
        "vertex",
        "label",
        if floors { "floor       " } else { "" },
        "at m",
        if human { "  check-in" } else { "" }
    )];
    for (i, &v) in walk.iter().enumerate() {
        let vx = &b.vertices[v];
        let label = label_cell(vx.label.as_deref(), label_w);
        let floor = if floors {
            format!("{:<12}", floor_name(b, vx.pos.floor))
        } else {
            String::new()
        };
        lines.push(format!(
            "  {:>4}  {:<id_w$}  {:<label_w$}  {floor}{:>8.1}{}",
            i + 1,
            printable(&vx.id),
            label,
            arc[i],
            if human && checks[i] { "  yes" } else { "" }
        ));
    }
    lines
}

/// The turn-by-turn sheet: where to start, then one line per decision point (a turn, a
/// check-in, a change of floor, the end) with the distance from the previous line, in the
/// words of a session's live guidance. Straight-on vertices without a check-in are folded
/// into the next line's distance.
pub fn instructions(b: &Building, walk: &[usize], model: &Surveyor) -> Vec<String> {
    let mut lines = Vec::new();
    let Some(&first) = walk.first() else {
        return lines;
    };
    let arc = arcs(b, walk);
    let checks = check_ins(b, walk, model);
    let human = matches!(model, Surveyor::Human { .. });
    let v0 = &b.vertices[first];
    let name0 = match &v0.label {
        Some(l) => format!("{} ({})", printable(&v0.id), printable(l)),
        None => printable(&v0.id),
    };
    lines.push(format!(
        "Start at {name0} on {}{}.",
        floor_name(b, v0.pos.floor),
        if human {
            "; check in there and start scanning"
        } else {
            ""
        }
    ));
    let n = walk.len();
    let mut last_arc = 0.0;
    let mut k = 0;
    for j in 1..n {
        let v = &b.vertices[walk[j]];
        let turn = if j + 1 >= n {
            Turn::Arrive
        } else {
            classify_turn(
                &b.vertices[walk[j - 1]].pos,
                &v.pos,
                &b.vertices[walk[j + 1]].pos,
            )
        };
        let check = human && checks[j];
        if turn == Turn::Straight && !check {
            continue;
        }
        k += 1;
        let mut sentence = guidance_sentence(
            arc[j] - last_arc,
            &printable(&v.id),
            v.label.as_deref().map(printable).as_deref(),
            turn,
            check,
        );
        if turn == Turn::ChangeFloor {
            // Which floor the stairs lead to, said once where it happens.
            let next = b.vertices[walk[j + 1]].pos.floor;
            if next != v.pos.floor {
                sentence = format!(
                    "{} (to {})",
                    sentence.trim_end_matches('.'),
                    floor_name(b, next)
                ) + ".";
            }
        }
        lines.push(format!("{k:>3}. step {:>3}  {sentence}", j + 1));
        last_arc = arc[j];
    }
    if n == 1 {
        lines.push("The walk is this one vertex: scan there and finish.".into());
    }
    lines
}

/// The walk, length and samples lines of a plan's summary, as `trailprint plan` and
/// `trailprint plans show` print them.
pub fn print_walk_summary(
    walk: &[String],
    length_m: f64,
    budget_m: f64,
    samples: u64,
    model: &Surveyor,
) {
    println!("walk          {}", walk.join(","));
    println!("length        {length_m:.1} m of the {budget_m} m budget");
    println!("samples       {samples} ({})", model_text(model));
}

/// The surveyor model in words: "robot, a scan every 0.5 m" or "human at 1.2 m/s, a scan
/// every 4 s (4.8 m), step-length error 5%, check-ins at turns over 30 degrees".
pub fn model_text(model: &Surveyor) -> String {
    match *model {
        Surveyor::Robot {
            interval_m: interval,
            ..
        } => format!("robot, a scan every {interval} m"),
        Surveyor::Human {
            speed_mps: speed,
            scan_interval_s: scan_interval,
            step_error,
            turn_threshold_deg,
            ..
        } => format!(
            "human at {speed} m/s, a scan every {scan_interval} s ({:.1} m), step-length \
             error {:.0}%, check-ins at turns over {turn_threshold_deg} degrees",
            speed * scan_interval,
            step_error * 100.0
        ),
    }
}

/// A survey robot's speed, m/s, unless `--robot-speed` says otherwise (`simulate` drives
/// its robot at it, `plan` and `plans show` time a robot's walk with it).
pub const ROBOT_SPEED_M_S: f64 = trailprint::surveyor::DEFAULT_ROBOT_SPEED_MPS;

/// The speed a walk is timed at: a human's own, or for a robot `robot_speed` (the
/// `--robot-speed` option, default [`ROBOT_SPEED_M_S`]).
pub fn walking_speed(model: &Surveyor, robot_speed: f64) -> f64 {
    match *model {
        Surveyor::Human { speed_mps, .. } => speed_mps,
        Surveyor::Robot { .. } => robot_speed,
    }
}

/// "about 2 min 16 s at 1.2 m/s, plus 2 s at each of 7 check-ins" for a walk of
/// `length_m`.
pub fn time_text(
    b: &Building,
    walk: &[usize],
    length_m: f64,
    model: &Surveyor,
    speed: f64,
) -> String {
    let checks = check_ins(b, walk, model).iter().filter(|&&c| c).count();
    let walking = length_m / speed;
    match model {
        Surveyor::Human { .. } => format!(
            "about {} at {speed} m/s ({} with a 2 s stop at each of the {checks} check-ins)",
            duration_text(walking),
            duration_text(walking + 2.0 * checks as f64)
        ),
        Surveyor::Robot { .. } => format!(
            "about {} at the robot's {speed} m/s (--robot-speed)",
            duration_text(walking)
        ),
    }
}

/// Prints the person's part of a plan: the time, then the steps table (or, with
/// `instructions`, the turn-by-turn sheet).
pub fn print_walk(
    b: &Building,
    walk: &[usize],
    length_m: f64,
    model: &Surveyor,
    robot_speed: f64,
    instructions_sheet: bool,
) {
    let speed = walking_speed(model, robot_speed);
    println!(
        "time          {}",
        time_text(b, walk, length_m, model, speed)
    );
    if instructions_sheet {
        println!();
        for l in instructions(b, walk, model) {
            println!("{l}");
        }
    } else {
        println!("steps         {} vertices", walk.len());
        for l in steps_table(b, walk, model) {
            println!("{l}");
        }
    }
}
