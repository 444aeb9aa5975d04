//! Prints a fuzz input as the target decodes it (its `Debug` form), to turn a
//! crash into a plain regression test.
//!
//! `cargo run --manifest-path fuzz/Cargo.toml --example decode -- complex_queries FILE`
//! (`quadric_intervals` for the other kernel target).

use komplex_fuzz::{decode, ComplexInput, QuadricInput};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, target, file] = &args[..] else {
        eprintln!("usage: decode (complex_queries | quadric_intervals) FILE");
        std::process::exit(2);
    };
    let bytes = std::fs::read(file).expect("readable input");
    match target.as_str() {
        "complex_queries" => println!("{:#?}", decode::<ComplexInput>(&bytes)),
        "quadric_intervals" => println!("{:#?}", decode::<QuadricInput>(&bytes)),
        t => {
            eprintln!("unknown target {t}");
            std::process::exit(2);
        }
    }
}
