//! The flight report as `shoot` and `replay` print it: first how the take looked, in a
//! director's words (the framing as a share of the frame's width, the drone's distance from
//! its path, how near it came to the actors); then the engineering figures, for the flight
//! and per shot; then the next step: where the log is and how to see it.

use std::fmt::Write as _;
use std::path::Path;

use dronecine_flight::report::{Figures, FlightReport};

/// How the flight the report is about ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// Every shot flown and the drone landed.
    Completed,
    /// Ended early (a failsafe, the operator).
    Aborted,
    /// The log ends before the flight did (`replay` of a cut log).
    Unfinished,
}

impl Ending {
    pub fn of(r: &FlightReport) -> Ending {
        match r.completed {
            true => Ending::Completed,
            false => Ending::Aborted,
        }
    }
}

/// What to do after reading the report.
#[derive(Clone, Copy, Debug)]
pub enum Next<'a> {
    /// `shoot` wrote this log: replay it, see it in Foxglove.
    Shot(&'a Path),
    /// `replay` read this log: see it in Foxglove.
    Replayed(&'a Path),
    /// Said elsewhere (a log that could not be written is an error of its own).
    Nothing,
}

/// The column the director's lines are wrapped at.
const WIDTH: usize = 100;

/// The report: the take in words, the figures, the next step.
pub fn render(
    r: &FlightReport,
    ending: Ending,
    profile: &str,
    controller: &str,
    next: Next,
) -> String {
    let mut s = dronecine_diag::docs::to_terminal(&in_words(r, ending), WIDTH);
    s.push('\n');
    s.push_str(&figures(r, ending, profile, controller));
    s.push_str(&next_step(next));
    s
}

/// One or two sentences on how the take looked.
fn in_words(r: &FlightReport, ending: Ending) -> String {
    let f = &r.figures;
    let cm = |m: f64| format!("{:.1} cm", m * 100.0);
    let mut look = Vec::new();
    // The framing error is a distance on a screen two units wide: half of it is the share of
    // the frame's width.
    look.push(match f.rms_framing_error {
        Some(e) => format!(
            "framing held to within {:.1}% of the frame's width",
            e * 50.0
        ),
        None => "no shot framed an actor".to_string(),
    });
    match (f.rms_position_error_m, f.max_position_error_m) {
        (Some(rms), Some(max)) => look.push(format!(
            "the drone within {} of its path ({} at worst)",
            cm(rms),
            cm(max)
        )),
        _ => look.push("the drone's position was never measured in a shot".to_string()),
    }
    if let Some(d) = f.closest_actor_m {
        look.push(format!("never nearer an actor than {d:.2} m"));
    }
    let look = format!("{}; {}", look[0], look[1..].join(", "));
    let reached = r.shots.last().map(|s| s.index + 1);
    let of = |n: usize| match r.scripted_shots >= n {
        true => format!("shot {n} of {}", r.scripted_shots),
        false => format!("shot {n}"),
    };
    let troubles = troubles(r);
    let mut s = match (ending, reached) {
        (Ending::Completed, _) => format!("The take is complete: {look}."),
        (Ending::Aborted, None) => "The take was ABORTED before its first shot.".to_string(),
        (Ending::Aborted, Some(n)) => format!(
            "The take was ABORTED in {} ({:.1} s of shots flown); until then {look}.",
            of(n),
            r.shots_time_s
        ),
        (Ending::Unfinished, None) => "The log ends before the first shot.".to_string(),
        (Ending::Unfinished, Some(n)) => format!(
            "The log ends in {}, before the flight did; until then {look}.",
            of(n)
        ),
    };
    if !troubles.is_empty() {
        s.push_str(&format!(" {}: see the log's /events.", troubles));
    }
    s
}

/// "1 failsafe and 2 director errors", or empty.
fn troubles(r: &FlightReport) -> String {
    let count = |n: u64, noun: &str| format!("{n} {noun}{}", if n == 1 { "" } else { "s" });
    let told: Vec<String> = [
        (r.failsafes, "failsafe"),
        (r.director_errors, "director error"),
        (r.faults, "controller fault"),
    ]
    .into_iter()
    .filter(|&(n, _)| n > 0)
    .map(|(n, noun)| count(n, noun))
    .collect();
    match told.len() {
        0 => String::new(),
        n => {
            let (last, rest) = (&told[n - 1], &told[..n - 1]);
            let mut t = rest.join(", ");
            if !t.is_empty() {
                t.push_str(" and ");
            }
            t.push_str(last);
            // A sentence starts with a capital.
            let mut c = t.chars();
            c.next()
                .map_or(t.clone(), |f| f.to_uppercase().chain(c).collect())
        }
    }
}

/// The five figures as printed: RMS and max position error in cm, RMS heading error in
/// degrees, RMS framing error, saturation in %; one with nothing to average (no measured
/// tick, no hold) as a dash.
fn cells(f: &Figures) -> [String; 5] {
    let fig = |x: Option<f64>, decimals: usize| {
        x.map_or("—".to_string(), |x| format!("{x:.decimals$}"))
    };
    let cm = |x: Option<f64>| x.map(|m| m * 100.0);
    [
        fig(cm(f.rms_position_error_m), 1),
        fig(cm(f.max_position_error_m), 1),
        fig(f.rms_heading_error_rad.map(f64::to_degrees), 2),
        fig(f.rms_framing_error, 3),
        fig(f.saturated_fraction.map(|x| x * 100.0), 1),
    ]
}

/// The engineering figures: the flight's, then each shot's.
fn figures(r: &FlightReport, ending: Ending, profile: &str, controller: &str) -> String {
    let mut s = String::new();
    let status = match ending {
        Ending::Completed => "completed",
        Ending::Aborted => "ABORTED",
        Ending::Unfinished => "unfinished log of a",
    };
    let _ = writeln!(
        s,
        "{status} flight with {profile} ({controller}): {:.1} s in the air, {:.1} s of shots",
        r.flight_time_s, r.shots_time_s
    );
    let [rms, max, heading, framing, saturated] = cells(&r.figures);
    if r.figures.rms_framing_error.is_some() {
        let _ = writeln!(
            s,
            "  framing: error RMS {framing} (the screen distance of the actors from their marks, \
             the frame two wide)"
        );
    }
    if r.figures.rms_position_error_m.is_some() {
        let _ = writeln!(
            s,
            "  tracking: position error RMS {rms} cm, max {max} cm; heading error RMS {heading}°; \
             the servo at a limit on {saturated}% of ticks"
        );
    }
    if let Some(d) = r.figures.closest_actor_m {
        let _ = write!(s, "  safety: closest to an actor {d:.2} m");
        // The tracking margin the drone used where the reference was near the actors.
        if let Some(c) = r.figures.cut_in_m {
            let _ = write!(
                s,
                "; up to {:.1} cm nearer one than its reference",
                c * 100.0
            );
        }
        s.push('\n');
    }
    s.push_str(&counts(r));
    let _ = writeln!(
        s,
        "  {:>4}  {:>8}  {:>8}  {:>8}  {:>8}  {:>7}  shot",
        "#", "RMS cm", "max cm", "head °", "framing", "sat %"
    );
    for shot in &r.shots {
        let mut label = shot.label.clone();
        if label.chars().count() > 60 {
            label = label.chars().take(59).collect::<String>() + "…";
        }
        let [rms, max, heading, framing, saturated] = cells(&shot.figures);
        let _ = writeln!(
            s,
            "  {:>4}  {rms:>8}  {max:>8}  {heading:>8}  {framing:>8}  {saturated:>7}  {label}",
            shot.index + 1,
        );
    }
    s
}

/// The failsafes, faults, missed deadlines, lateness and director errors, when there were any.
fn counts(r: &FlightReport) -> String {
    let mut s = String::new();
    let count = |n: u64, noun: &str| format!("{n} {noun}{}", if n == 1 { "" } else { "s" });
    if r.failsafes + r.faults + r.deadline_misses > 0 {
        let _ = writeln!(
            s,
            "  {}, {}, {} (see the log's /events)",
            count(r.failsafes, "failsafe"),
            count(r.faults, "controller fault"),
            count(r.deadline_misses, "missed deadline")
        );
    }
    if let Some(l) = r.lateness {
        let _ = writeln!(
            s,
            "  timing: {} ticks ran {:.0} µs late at the median, {:.0} µs at the 99th \
             percentile, {:.1} ms at worst",
            l.ticks,
            l.p50_s * 1e6,
            l.p99_s * 1e6,
            l.max_s * 1e3
        );
    }
    if r.director_errors > 0 {
        let _ = writeln!(
            s,
            "  {} against the live actors (see the log's /events)",
            count(r.director_errors, "director error")
        );
    }
    s
}

/// Where the log is and how to see it.
fn next_step(next: Next) -> String {
    let foxglove =
        "open it in Foxglove (https://foxglove.dev): the flight in 3D and every figure over time";
    match next {
        Next::Shot(log) => format!(
            "\nflight log: {log}\n  replay it: dronecine replay {log}\n  see it: {foxglove}\n",
            log = log.display()
        ),
        Next::Replayed(log) => format!("\nflight log: {}\n  see it: {foxglove}\n", log.display()),
        Next::Nothing => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::{render, Ending, Next};
    use dronecine_flight::report::{Figures, FlightReport, ShotReport};
    use std::path::Path;

    fn measured() -> Figures {
        Figures {
            rms_position_error_m: Some(0.0123),
            max_position_error_m: Some(0.05),
            rms_heading_error_rad: Some(0.01),
            rms_framing_error: Some(0.021),
            saturated_fraction: Some(0.5),
            closest_actor_m: Some(0.623),
            cut_in_m: None,
            measured_ticks: 100,
        }
    }

    fn shot(index: usize, figures: Figures) -> ShotReport {
        ShotReport {
            index,
            label: format!("shot {index}"),
            start_s: 0.0,
            end_s: 1.0,
            figures,
        }
    }

    fn report() -> FlightReport {
        let blind = Figures {
            saturated_fraction: Some(0.0),
            ..Figures::default()
        };
        FlightReport {
            completed: true,
            flight_time_s: 10.0,
            shots_time_s: 2.0,
            scripted_shots: 2,
            figures: measured(),
            failsafes: 0,
            faults: 0,
            deadline_misses: 0,
            lateness: None,
            director_errors: 0,
            latency_mean_s: None,
            latency_max_s: None,
            shots: vec![shot(0, measured()), shot(1, blind)],
        }
    }

    const LOG: &str = "flights/x-20261128-120930.mcap";

    /// The report's first paragraph, unwrapped, and the lines after it.
    fn split(text: &str) -> (String, Vec<&str>) {
        let (lead, rest) = text.split_once("\n\n").expect("a paragraph first");
        (lead.replace('\n', " "), rest.lines().collect())
    }

    fn text(r: &FlightReport, ending: Ending) -> String {
        render(r, ending, "ardrone2", "lqg", Next::Nothing)
    }

    /// A completed take's report, with `next`.
    fn then(r: &FlightReport, next: Next) -> String {
        render(r, Ending::Completed, "ardrone2", "lqg", next)
    }

    #[test]
    fn the_report_leads_with_the_take_in_words_then_figures_then_the_next_step() {
        let r = report();
        let shot = then(&r, Next::Shot(Path::new(LOG)));
        let (lead, lines) = split(&shot);
        assert_eq!(
            lead,
            "The take is complete: framing held to within 1.1% of the frame's width; the drone \
             within 1.2 cm of its path (5.0 cm at worst), never nearer an actor than 0.62 m."
        );
        assert!(shot
            .split("\n\n")
            .next()
            .unwrap()
            .lines()
            .all(|l| l.chars().count() <= 100));
        assert_eq!(
            lines[..4],
            [
                "completed flight with ardrone2 (lqg): 10.0 s in the air, 2.0 s of shots",
                "  framing: error RMS 0.021 (the screen distance of the actors from their marks, \
                 the frame two wide)",
                "  tracking: position error RMS 1.2 cm, max 5.0 cm; heading error RMS 0.57°; the \
                 servo at a limit on 50.0% of ticks",
                "  safety: closest to an actor 0.62 m",
            ]
        );
        assert!(!shot.contains("director error"), "{shot}");
        // A shot never measured: dashes, not zeros.
        let row = lines.iter().find(|l| l.ends_with("shot 1")).unwrap();
        let cells: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(cells[..6], ["2", "—", "—", "—", "—", "0.0"], "{shot}");
        let foxglove =
            "  see it: open it in Foxglove (https://foxglove.dev): the flight in 3D and \
                        every figure over time\n";
        assert!(
            shot.ends_with(&format!(
                "\n\nflight log: {LOG}\n  replay it: dronecine replay {LOG}\n{foxglove}"
            )),
            "{shot}"
        );
        let replayed = then(&r, Next::Replayed(Path::new(LOG)));
        assert!(
            replayed.ends_with(&format!("\n\nflight log: {LOG}\n{foxglove}")),
            "{replayed}"
        );
        assert!(!text(&r, Ending::Completed).contains("flight log"));
    }

    #[test]
    fn an_aborted_take_says_where_and_why() {
        let mut r = report();
        r.completed = false;
        r.failsafes = 1;
        r.director_errors = 2;
        r.scripted_shots = 5;
        let aborted = text(&r, Ending::of(&r));
        assert_eq!(
            split(&aborted).0,
            "The take was ABORTED in shot 2 of 5 (2.0 s of shots flown); until then framing \
             held to within 1.1% of the frame's width; the drone within 1.2 cm of its path \
             (5.0 cm at worst), never nearer an actor than 0.62 m. 1 failsafe and 2 director \
             errors: see the log's /events."
        );
        assert!(
            aborted.contains("\n\nABORTED flight with ardrone2 (lqg)"),
            "{aborted}"
        );
        assert!(
            aborted.contains(
                "\n  2 director errors against the live actors (see the log's /events)\n"
            ),
            "{aborted}"
        );
        let unfinished = text(&r, Ending::Unfinished);
        assert!(
            unfinished.starts_with(
                "The log ends in shot 2 of 5, before the flight did; until then framing"
            ),
            "{unfinished}"
        );
        assert!(
            unfinished.contains("\n\nunfinished log of a flight with"),
            "{unfinished}"
        );
        // A script the log's reader could not read again: no count of its shots.
        r.scripted_shots = 0;
        assert!(text(&r, Ending::Aborted).starts_with("The take was ABORTED in shot 2 (2.0 s"));
        r.shots.clear();
        let before = text(&r, Ending::Aborted);
        assert_eq!(
            split(&before).0,
            "The take was ABORTED before its first shot. 1 failsafe and 2 director errors: see \
             the log's /events."
        );
        assert!(text(&r, Ending::Unfinished).starts_with("The log ends before the first shot."));
    }

    /// Paths frame nobody; a drone never measured has no distance to its path.
    #[test]
    fn a_take_of_paths_or_unmeasured_says_so() {
        let mut r = report();
        r.figures.rms_framing_error = None;
        r.figures.closest_actor_m = None;
        let paths = text(&r, Ending::Completed);
        assert_eq!(
            split(&paths).0,
            "The take is complete: no shot framed an actor; the drone within 1.2 cm of its path \
             (5.0 cm at worst)."
        );
        assert!(
            !paths.contains("  framing:") && !paths.contains("  safety:"),
            "{paths}"
        );
        r.figures = Figures::default();
        let blind = text(&r, Ending::Completed);
        assert_eq!(
            split(&blind).0,
            "The take is complete: no shot framed an actor; the drone's position was never \
             measured in a shot."
        );
        assert!(!blind.contains("  tracking:"), "{blind}");
        let mut r = report();
        r.figures.cut_in_m = Some(0.0614);
        assert!(
            text(&r, Ending::Completed).contains(
                "\n  safety: closest to an actor 0.62 m; up to 6.1 cm nearer one than its \
                 reference\n"
            ),
            "{}",
            text(&r, Ending::Completed)
        );
    }
}
