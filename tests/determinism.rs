//! The image does not depend on the number of worker threads: every
//! channel's samples are bit-identical (decoded with the `exr` crate), and so
//! are the files.

use exr::prelude::{read_all_flat_layers_from_file, FlatSamples};

use crate::support::{all_scenes, komplex_ok, tempdir};

/// Every channel of the EXR at `path` as (name, sample bits).
fn pixels(path: &std::path::Path) -> Vec<(String, Vec<u32>)> {
    let image = read_all_flat_layers_from_file(path).unwrap();
    assert_eq!(image.layer_data.len(), 1);
    image.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| {
            let bits = match &c.sample_data {
                FlatSamples::F16(v) => v.iter().map(|x| u32::from(x.to_bits())).collect(),
                FlatSamples::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
                FlatSamples::U32(v) => v.clone(),
            };
            (c.name.to_string(), bits)
        })
        .collect()
}

#[test]
fn thread_count_does_not_change_a_bit() {
    let dir = tempdir();
    for s in all_scenes() {
        for samples in ["1", "3"] {
            let mut images = vec![];
            for threads in [Some("1"), Some("2"), Some("3"), None] {
                let out = dir.path().join(format!("t{}.exr", threads.unwrap_or("default")));
                let mut args = vec!["render", s.to_str().unwrap(), "-o", out.to_str().unwrap()];
                args.extend(["--width", "40", "--height", "30", "--samples", samples]);
                if let Some(n) = threads {
                    args.extend(["--threads", n]);
                }
                komplex_ok(dir.path(), &args);
                images.push((threads, pixels(&out), std::fs::read(&out).unwrap()));
            }
            let (_, first, first_bytes) = &images[0];
            assert_eq!(first.len(), 10, "channels");
            // Not all one colour, so the comparison can fail.
            assert!(first.iter().any(|(_, bits)| bits.iter().any(|b| *b != bits[0])));
            for (threads, image, bytes) in &images[1..] {
                for ((name, a), (_, b)) in first.iter().zip(image) {
                    assert!(
                        a == b,
                        "{} samples {samples}: channel {name} differs with --threads {threads:?}",
                        s.display()
                    );
                }
                assert!(bytes == first_bytes, "{}: the files differ with --threads {threads:?}", s.display());
            }
        }
    }
}
