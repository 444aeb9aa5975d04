//! Command-line behaviour: commands, exit codes, output files.

use crate::support::{komplex, root, text};

#[test]
fn schema_prints_json() {
    let o = komplex(&root(), &["schema"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("schema is JSON");
    assert_eq!(v["$schema"], "http://json-schema.org/draft-07/schema#");
}
