//! `simulate --animate`: the figures follow the scene (the rod's end stays on its floor, a
//! body's axes stay unit vectors, springs know their fixed ends), a `draw` line leaves the
//! derivation alone, the page is the same bytes on every run and names nothing on a network,
//! and, in a real browser, it plays: stepping the slider changes the picture and the console
//! stays free of errors; a scene with contacts carries each one's mode per frame and its
//! events into the page.
//!
//! The browser part needs Chromium and python3 (`tests/browser/check_page.py` drives it). Where
//! either is missing, it says so and passes, unless `LAGRANGE_BROWSER_TEST=required` (as
//! `.ci/run` sets), when a missing browser is a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use simulation::animate::{Animation, FigureKind};

fn example(rel: &str) -> String {
    std::fs::read_to_string(lagrange_tests::examples_dir().join(rel)).expect("readable example")
}

fn animation(rel: &str) -> Animation {
    let options = simulation::Options { animate: true, samples: 300, ..Default::default() };
    let outcome = simulation::simulate(&example(rel), &options)
        .unwrap_or_else(|e| panic!("{rel} does not simulate: {e:?}"));
    assert!(outcome.run.fault.is_none(), "{rel} faulted");
    outcome.animation.expect("an animation was asked for")
}

fn figure<'a>(animation: &'a Animation, label: &str) -> &'a simulation::animate::Figure {
    animation
        .figures
        .iter()
        .find(|f| f.label == label)
        .unwrap_or_else(|| panic!("no figure `{label}` among {:?}", labels(animation)))
}

fn labels(animation: &Animation) -> Vec<&str> {
    animation.figures.iter().map(|f| f.label.as_str()).collect()
}

#[test]
fn the_falling_rod_keeps_its_end_on_the_floor() {
    let a = animation("ps5/falling_rod.lag");
    assert_eq!(a.dimension, 2);
    assert!(a.times.len() > 50, "{} frames", a.times.len());
    assert!(
        matches!(figure(&a, "rod").kind, FigureKind::Body { axis_length } if axis_length > 0.5)
    );
    let rod = a
        .figures
        .iter()
        .find(|f| f.kind == FigureKind::Line && f.label.contains("rod.position"))
        .expect("the rod is drawn");
    for frame in &rod.frames {
        // From end B, on the floor, to end A, a rod's length away.
        assert!(frame[1].abs() < 1e-9, "end B left the floor: {frame:?}");
        let (dx, dy) = (frame[2] - frame[0], frame[3] - frame[1]);
        let length = (dx * dx + dy * dy).sqrt();
        assert!((length - 1.0).abs() < 1e-9, "the rod is {length} long");
    }
    let floor = figure(&a, "draw line from (-L, 0) to (L, 0)");
    assert!(floor.frames.iter().all(|f| f == &[-1.0, 0.0, 1.0, 0.0]));
    // The energy error is the integrator's: tiny.
    assert!(a.conservative);
    assert!(a.energy_error.iter().all(|e| e.abs() < 1e-6));
}

#[test]
fn bodies_in_space_carry_unit_axes() {
    let a = animation("space/heavy_top.lag");
    assert_eq!(a.dimension, 3);
    let top = figure(&a, "top");
    for frame in &top.frames {
        assert_eq!(frame.len(), 3 + 9, "a centre and three axes");
        for axis in frame[3..].chunks(3) {
            let norm = axis.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() < 1e-9, "an axis of length {norm}");
        }
    }
}

#[test]
fn springs_and_dampers_know_their_fixed_ends() {
    let a = animation("classics/spring_pendulum_cartesian.lag");
    let rope = figure(&a, "rope");
    assert_eq!(rope.kind, FigureKind::Link { damper: false, fixed: [true, false] });
    let drag = figure(&a, "drag");
    assert_eq!(drag.kind, FigureKind::Link { damper: true, fixed: [true, false] });
    let bob = figure(&a, "bob");
    assert_eq!(bob.kind, FigureKind::Particle { mass: 1.0 });
    for (link, dot) in rope.frames.iter().zip(&bob.frames) {
        assert_eq!(&link[..2], &[0.0, 0.0]);
        assert_eq!(&link[2..], &dot[..]);
    }
}

#[test]
fn a_drawing_leaves_the_derivation_alone() {
    for rel in ["ps5/falling_rod.lag", "ps5/rolling_disk.lag", "space/double_pendulum_3d.lag"] {
        let source = example(rel);
        assert!(source.contains("\ndraw "), "{rel} draws nothing");
        let without: String =
            source.lines().filter(|l| !l.starts_with("draw ")).map(|l| format!("{l}\n")).collect();
        for format in [cli::Format::Text, cli::Format::Json] {
            assert_eq!(
                cli::derive(rel, &source, format),
                cli::derive(rel, &without, format),
                "{rel}: a draw line changed the derivation"
            );
        }
    }
}

/// A ball bouncing on its floor: the page carries the contact's mode at every frame (closed
/// from where it settles, open before, and at each impact's two frames open on both sides),
/// the events with their times, and the energy error less what the impacts took.
#[test]
fn the_page_carries_each_contacts_mode_and_its_events() {
    let a = animation("contacts/bouncing_ball.lag");
    assert_eq!(a.contacts.len(), 1);
    let floor = &a.contacts[0];
    assert_eq!((floor.name.as_str(), floor.closed.len()), ("floor", a.times.len()));
    let settled = a
        .contact_events
        .iter()
        .find(|m| m.kind == sim::ModeChange::Settled)
        .expect("the ball settles within the run")
        .time;
    let (h0, g, e) = (1.0, 9.81, 0.8);
    let accumulation = f64::sqrt(2.0 * h0 / g) * (1.0 + e) / (1.0 - e);
    assert!((settled - accumulation).abs() < 1e-6 * accumulation, "settled at {settled}");
    for (k, (&t, &closed)) in a.times.iter().zip(&floor.closed).enumerate() {
        // The frame before the settling jump is still open; the one after, closed.
        let after = t > settled || (t == settled && a.times[k - 1] == t);
        assert_eq!(closed, after, "frame {k} at t = {t}");
    }
    let impacts = a.contact_events.iter().filter(|m| m.kind == sim::ModeChange::Impact).count();
    assert!(impacts > 10, "{impacts} impacts");
    // An impact is two frames at one time; the energy error leaves out what it took.
    let jumps = a.times.windows(2).filter(|w| w[0] == w[1]).count();
    assert_eq!(jumps, impacts + 1, "a frame pair at each impact and at the settling");
    assert!(a.energy_error.iter().all(|e| e.abs() < 1e-5), "{:?}", a.energy_error);

    let page = cli::animate::page(&a, "ball");
    let closed: Vec<String> = floor.closed.iter().map(|&c| u8::from(c).to_string()).collect();
    let expected = format!(r#""contacts":[{{"name":"floor","closed":[{}]}}]"#, closed.join(","));
    assert!(page.contains(&expected), "the modes are not in the page");
    assert!(page.contains(
        r#""contact_events":[{"t":0.451524,"contact":0,"kind":"impact","closed":false}"#
    ));
    assert_eq!(page.matches(r#""kind":"impact""#).count(), impacts);
    assert_eq!(page.matches(r#""kind":"settled""#).count(), 1);
    // The page shows them: a badge per contact, a flash at impacts, marks on the time axis.
    for script in ["showContacts(now)", "drawFlash(now)", "contactEvents"] {
        assert!(page.contains(script), "no `{script}` in the page");
    }
}

/// The pages the browser opens: a scene in the plane with a body, one with particles, one in
/// space, and a ball bouncing on its floor (a contact opening and closing).
const PAGES: [&str; 4] = [
    "ps5/falling_rod.lag",
    "classics/double_pendulum.lag",
    "space/double_pendulum_3d.lag",
    "contacts/bouncing_ball.lag",
];

fn page(rel: &str) -> String {
    cli::animate::page(&animation(rel), rel)
}

#[test]
fn pages_are_the_same_bytes_and_name_no_network() {
    for rel in PAGES {
        let first = page(rel);
        assert_eq!(first, page(rel), "{rel}: two runs give different pages");
        for reference in
            ["://", "<link", " src=", "url(", "@import", "fetch(", "XMLHttpRequest", "WebSocket"]
        {
            assert!(!first.contains(reference), "{rel}: the page contains `{reference}`");
        }
        assert!(first.starts_with("<!DOCTYPE html>"));
        assert!(first.contains(r#""dimension":"#));
    }
}

/// Chromium, where this machine has one.
fn chromium() -> Option<PathBuf> {
    let candidates = std::env::var_os("LAGRANGE_CHROMIUM")
        .map(PathBuf::from)
        .into_iter()
        .chain(["chromium", "chromium-browser"].map(PathBuf::from));
    candidates.into_iter().find(|c| {
        Command::new(c)
            .args(["--headless", "--no-sandbox", "--version"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

fn python() -> Option<&'static str> {
    Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
        .then_some("python3")
}

#[test]
fn the_page_plays_in_a_browser() {
    let required = std::env::var("LAGRANGE_BROWSER_TEST").is_ok_and(|v| v == "required");
    let (Some(chromium), Some(python)) = (chromium(), python()) else {
        let missing = "Chromium or python3 is not installed";
        assert!(!required, "{missing}, and LAGRANGE_BROWSER_TEST=required");
        eprintln!("skipped: {missing}; `.ci/run` installs Chromium and runs this for real");
        return;
    };
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("animate");
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("browser/check_page.py");
    for rel in PAGES {
        let path = dir.join(rel.replace('/', "__").replace(".lag", ".html"));
        std::fs::write(&path, page(rel)).expect("page written");
        let run = Command::new(python)
            .arg(&script)
            .arg(&path)
            .arg("--chromium")
            .arg(&chromium)
            .output()
            .expect("the browser check runs");
        let report = format!(
            "{}{}",
            String::from_utf8_lossy(&run.stdout),
            String::from_utf8_lossy(&run.stderr)
        );
        assert!(run.status.success(), "{rel} in Chromium:\n{report}");
        eprint!("{report}");
    }
}
