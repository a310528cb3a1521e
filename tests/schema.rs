//! The add-on reads the scene schema from a committed copy
//! (blender/scene_schema.json); this fails when it differs from what
//! `aurora scene --schema` prints (regenerate it with
//! `aurora scene --schema > blender/scene_schema.json`).

#[test]
fn committed_schema_matches_the_binary() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("blender/scene_schema.json");
    let committed = std::fs::read_to_string(&path).expect("blender/scene_schema.json");
    let now = aurora::scene::schema::schema_json();
    assert!(
        committed == now,
        "blender/scene_schema.json is stale: run `aurora scene --schema > blender/scene_schema.json`"
    );
    // And the binary prints the same.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_aurora")).args(["scene", "--schema"]).output().unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8(out.stdout).unwrap(), now);
}
