//! A gallery of malformed or mistaken scenes (`tests/bad/*.lag`): each is refused with exit
//! code 2 and its diagnostic, pinned by a snapshot; none panics.

use std::path::Path;

#[test]
fn every_bad_scene_gets_its_diagnostic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("bad");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/bad exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "lag"))
        .collect();
    files.sort();
    assert!(files.len() >= 30, "only {} bad scenes", files.len());
    for path in files {
        let name = path.file_stem().expect("name").to_string_lossy().into_owned();
        let source = std::fs::read_to_string(&path).expect("readable");
        let shown = format!("{name}.lag");
        let result = cli::check::check_file(&shown, &source);
        assert_eq!(result.exit_code, 2, "{name} is not refused:\n{}", result.report);
        assert!(
            result.report.contains(&format!("{shown}:")),
            "{name}: no location in\n{}",
            result.report
        );
        assert!(result.report.contains('^'), "{name}: no caret in\n{}", result.report);
        insta::with_settings!({ input_file => &path, omit_expression => true }, {
            insta::assert_snapshot!(format!("bad@{name}"), result.report);
        });
    }
}
