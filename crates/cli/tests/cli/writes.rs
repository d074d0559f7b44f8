//! What the files `lagrange` writes replace: a read-only file is refused, a symbolic link is
//! written through, modes follow the umask or the replaced file, and no command writes over
//! the file it reads.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;

use super::{lagrange, stderr, Scratch};

const SCENE: &str = "param m = 1 kg, k = 4 N/m\ncoord x = 1\n\
                     particle p { mass m; position (x, 0) }\npotential k*x^2/2\n";

fn mode(path: &Path) -> u32 {
    std::fs::metadata(path).expect("the file is there").permissions().mode() & 0o7777
}

#[test]
fn a_read_only_file_is_not_replaced() {
    let scratch = Scratch::new("read-only");
    let target = scratch.file("kept.txt");
    std::fs::write(&target, "precious").expect("write");
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o444)).expect("chmod");
    // The refusal is by the mode, so it holds for root too, whom EACCES would not stop.
    let error = cli::write_atomically(&target, "replaced").expect_err("a read-only file");
    assert!(error.to_string().contains("read-only"), "{error}");
    assert_eq!(std::fs::read_to_string(&target).expect("read"), "precious");
    assert_eq!(mode(&target), 0o444);

    std::fs::write(scratch.file("s.lag"), SCENE).expect("write");
    let out = lagrange(&["derive", &scratch.path("s.lag"), "--out", &scratch.path("kept.txt")]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let message = stderr(&out);
    assert!(message.contains("kept.txt") && message.contains("read-only"), "{message}");
    assert_eq!(std::fs::read_to_string(&target).expect("read"), "precious");
}

#[test]
fn a_symbolic_link_is_written_through() {
    let scratch = Scratch::new("symlink");
    std::fs::create_dir_all(scratch.file("real")).expect("dir");
    let real = scratch.file("real/data.csv");
    std::fs::write(&real, "old").expect("write");
    std::fs::set_permissions(&real, std::fs::Permissions::from_mode(0o640)).expect("chmod");
    // Relative, as links usually are: relative to the link's folder, not the process's.
    let link = scratch.file("link.csv");
    std::os::unix::fs::symlink("real/data.csv", &link).expect("symlink");
    cli::write_atomically(&link, "new").expect("written through the link");
    assert!(std::fs::symlink_metadata(&link).expect("link").file_type().is_symlink());
    assert_eq!(std::fs::read_to_string(&real).expect("read"), "new");
    assert_eq!(mode(&real), 0o640, "the replaced file keeps its mode");

    cli::write_atomically_by(&link, |tmp| std::fs::write(tmp, "by a writer")).expect("written");
    assert!(std::fs::symlink_metadata(&link).expect("link").file_type().is_symlink());
    assert_eq!(std::fs::read_to_string(&real).expect("read"), "by a writer");

    // A link to a file not there yet makes the file.
    let dangling = scratch.file("dangling.csv");
    std::os::unix::fs::symlink("real/later.csv", &dangling).expect("symlink");
    cli::write_atomically(&dangling, "made").expect("written through the link");
    assert_eq!(std::fs::read_to_string(scratch.file("real/later.csv")).expect("read"), "made");
}

#[test]
fn a_new_file_follows_the_umask_and_a_replaced_one_keeps_its_mode() {
    let scratch = Scratch::new("umask");
    std::fs::write(scratch.file("s.lag"), SCENE).expect("write");
    let derive_under = |umask: &str, out: &str| {
        let script = format!(
            "umask {umask} && exec \"$0\" derive '{}' --out '{}'",
            scratch.path("s.lag"),
            scratch.path(out)
        );
        let out = Command::new("sh")
            .args(["-c", &script, env!("CARGO_BIN_EXE_lagrange")])
            .output()
            .expect("sh runs");
        assert!(out.status.success(), "{}", stderr(&out));
    };
    derive_under("027", "new.txt");
    assert_eq!(mode(&scratch.file("new.txt")), 0o640);
    derive_under("022", "wide.txt");
    assert_eq!(mode(&scratch.file("wide.txt")), 0o644);
    std::fs::set_permissions(scratch.file("wide.txt"), std::fs::Permissions::from_mode(0o600))
        .expect("chmod");
    derive_under("000", "wide.txt");
    assert_eq!(mode(&scratch.file("wide.txt")), 0o600);
}

#[test]
fn no_command_writes_over_the_file_it_reads() {
    let scratch = Scratch::new("own-input");
    let scene = scratch.file("s.lag");
    std::fs::write(&scene, SCENE).expect("write");
    std::os::unix::fs::symlink("s.lag", scratch.file("alias.lag")).expect("symlink");
    let dotted = format!("{}/./s.lag", scratch.0.display());
    for args in [
        vec!["derive", &scratch.path("s.lag"), "--out", &scratch.path("s.lag")],
        vec!["derive", &scratch.path("s.lag"), "--out", &dotted],
        vec!["derive", &scratch.path("s.lag"), "--out", &scratch.path("alias.lag")],
        vec!["codegen", &scratch.path("s.lag"), "--out", &scratch.path("s.lag")],
        vec!["linearize", &scratch.path("s.lag"), "--about", "x=0", "--out", &dotted],
    ] {
        let out = lagrange(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("would replace"), "{args:?}: {}", stderr(&out));
        assert_eq!(std::fs::read_to_string(&scene).expect("read"), SCENE, "{args:?}");
    }

    let made = lagrange(&[
        "simulate",
        &scratch.path("s.lag"),
        "--output",
        "x,x',x''",
        "--out",
        &scratch.path("traj.csv"),
    ]);
    assert!(made.status.success(), "{}", stderr(&made));
    let trajectory = std::fs::read_to_string(scratch.file("traj.csv")).expect("read");
    let out = lagrange(&[
        "inverse-dynamics",
        &scratch.path("s.lag"),
        "--trajectory",
        &scratch.path("traj.csv"),
        "--out",
        &scratch.path("traj.csv"),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--trajectory"), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(scratch.file("traj.csv")).expect("read"), trajectory);
}
