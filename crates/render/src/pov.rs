//! Export to POV-Ray 3.7 scene language, for comparison renders and the
//! mask test.
//!
//! The export reads the converted [`World`], so POV-Ray sees exactly the
//! solids the kernel traces:
//!
//! - the camera by explicit `direction`/`right`/`up` vectors in pixel units
//!   (`direction` of length `sqrt(W²+H²)/(2·tan(aperture/2))`, `right` =
//!   `W·R`, `up` = `H·U`). POV forms a pixel's ray as `direction + x·right +
//!   y·up` with `x, y ∈ (−½, ½)`, so handing it our own world-space `R = D × U`
//!   gives our image, not its mirror; no `look_at`/`angle`, which would
//!   impose POV's left-handed default;
//! - each quadric diagonalised: with `A = R Λ Rᵀ` and `y = Rᵀ(x − c)`,
//!   `f = yᵀΛy + 2(Rᵀw)·y + k`, written as `quadric { <λ>, <0,0,0>, <2Rᵀw>, k }`
//!   plus `matrix` `x = R y + c`. POV can only bound quadrics without mixed
//!   terms, so this is what lets it bound an ellipsoid however it is rotated;
//! - half-spaces as `plane { n/|n|, -d/|n| }` around their reference point;
//! - mostly-negative quadrics (complements) as the positive quadric plus
//!   `inverse`, so POV's bounding sees the ordinary solid;
//! - blocks as `intersection` inside one `union`.
//!
//! With [`PovOptions::mask`] every block gets a flat colour encoding its
//! 1-based id ([`mask_color`]), no lights and `assumed_gamma 1.0`, so POV's
//! picture (written with `File_Gamma=1.0`) is the `id.block` channel.
//!
//! ```
//! let text = r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 8, "height": 6 },
//!                 "blocks": [ { "objects": [ { "sphere": { "radius": 2 } } ] } ] }"#;
//! let world = render::format::SceneFile::load_str(text).unwrap();
//! let pov = render::pov::export(&world, render::pov::PovOptions { mask: true }).unwrap();
//! assert!(pov.contains("quadric {") && pov.contains("ambient 1 diffuse 0"));
//! ```

use std::fmt::Write;

use quadric::nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use quadric::{HalfSpace, Quadric, Solid};

use crate::camera::Projection;
use crate::error::Error;
use crate::world::{Material, Model, World};

/// What to write.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PovOptions {
    /// Flat id colours instead of materials and lights.
    pub mask: bool,
}

/// The mask colour of the block with 1-based `id`: the id's bytes, least
/// significant in red (`r + 256·g + 65536·b = id`), as 8-bit values.
pub fn mask_color(id: u32) -> [u8; 3] {
    [(id & 0xff) as u8, ((id >> 8) & 0xff) as u8, ((id >> 16) & 0xff) as u8]
}

/// A number as POV reads it back exactly (Rust's shortest round-trip form;
/// never exponent notation, which POV does not parse).
struct Num(f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // -0 prints as "-0", which POV reads fine, but keep files tidy.
        let x = if self.0 == 0.0 { 0.0 } else { self.0 };
        write!(f, "{x}")
    }
}

fn v3(v: &Vector3<f64>) -> String {
    format!("<{}, {}, {}>", Num(v.x), Num(v.y), Num(v.z))
}

/// The most blocks of a scene with instances the export writes: it writes
/// every placed copy as a block of its own.
pub const MAX_BLOCKS_EXPORTED: usize = 1 << 16;

/// The scene as POV-Ray 3.7 source. A scene with instances is written
/// expanded, each placed block on its own, up to [`MAX_BLOCKS_EXPORTED`]
/// blocks; more are an error.
pub fn export(world: &World, options: PovOptions) -> Result<String, Error> {
    let n = world.complex.len();
    if world.is_instanced() && n > MAX_BLOCKS_EXPORTED {
        return Err(Error::Options(format!(
            "export-pov: the scene has {n} blocks (instances and lattices expanded), more than the \
             {MAX_BLOCKS_EXPORTED} it writes out one by one"
        )));
    }
    let mut out = String::new();
    // Writing to a String cannot fail.
    let _ = write_scene(&mut out, world, options);
    Ok(out)
}

fn write_scene(out: &mut String, world: &World, options: PovOptions) -> std::fmt::Result {
    let cam = &world.camera;
    let (w, h) = (f64::from(cam.width()), f64::from(cam.height()));
    writeln!(
        out,
        "// Exported by komplex export-pov{}. Render at +W{} +H{}.",
        if options.mask { " --mask" } else { "" },
        cam.width(),
        cam.height()
    )?;
    writeln!(out, "#version 3.7;")?;
    let s = &world.settings;
    if options.mask {
        writeln!(out, "global_settings {{ assumed_gamma 1.0 ambient_light rgb 1 }}")?;
        writeln!(out, "background {{ rgb 0 }}")?;
    } else {
        writeln!(
            out,
            "global_settings {{ assumed_gamma 1.0 ambient_light rgb 1 max_trace_level {} }}",
            s.max_depth.saturating_add(1).min(256)
        )?;
        writeln!(out, "background {{ rgb {} }}", v3(&Vector3::from(s.background)))?;
    }
    // Orthographic: `right` and `up` span the image rectangle in world units.
    let (kind, scale, forward) = match cam.projection() {
        Projection::Perspective => ("perspective", 1.0, cam.focal_distance()),
        Projection::Orthographic { .. } => ("orthographic", cam.pixel_size(), 1.0),
    };
    writeln!(
        out,
        "camera {{\n  {kind}\n  location {}\n  direction {}\n  right {}\n  up {}\n}}",
        v3(&cam.eye().coords),
        v3(&(forward * cam.direction())),
        v3(&(scale * w * cam.right())),
        v3(&(scale * h * cam.up()))
    )?;
    if !options.mask {
        for l in &world.lights {
            let shadowless = if s.shadows { "" } else { " shadowless" };
            writeln!(out, "light_source {{ {} color rgb {}{shadowless} }}", v3(&l.position.coords), v3(&l.diffuse))?;
        }
    }
    writeln!(out, "union {{")?;
    for b in 0..world.complex.len() {
        let id = b as u32 + 1;
        let key = complex::BlockId(b as u32);
        // A placed block, moved from its definition's frame to the world.
        let resolved = world.complex.resolve(key);
        let placed;
        let block = match &resolved.to_world {
            None => resolved.block,
            Some(t) => {
                let solids = resolved.block.solids().iter().map(|s| s.transformed(t)).collect();
                let b = resolved.block;
                placed = complex::Block::new(b.name(), solids, b.opacity(), b.material());
                match &placed {
                    Ok(block) => block,
                    // A placement whose solids do not stay finite: left out.
                    Err(_) => continue,
                }
            }
        };
        // A one-solid block is the solid itself: POV warns about a CSG of
        // one member, and the wrapper would only cost it time.
        let single = block.solids().len() == 1;
        let indent = if single { "  " } else { "    " };
        writeln!(out, "  // block {} {}", id, block.name().replace(['\n', '\r'], " "))?;
        if !single {
            writeln!(out, "  intersection {{")?;
        }
        for (j, solid) in block.solids().iter().enumerate() {
            write!(out, "{indent}")?;
            match solid {
                Solid::Quadric(q) => write_quadric(out, q)?,
                Solid::HalfSpace(hs) => write_plane(out, hs)?,
            }
            // The solid is still open: its texture goes inside its braces.
            if !options.mask {
                let m = world.surface_material(key, j as u32);
                write!(out, " texture {{ {} }}", texture(m, &s.ambient))?;
            }
            if single {
                write!(out, "{}", block_modifiers(world, key, id, options))?;
            }
            writeln!(out, " }}")?;
        }
        if !single {
            let modifiers = block_modifiers(world, key, id, options);
            if !modifiers.is_empty() {
                writeln!(out, "   {modifiers}")?;
            }
            writeln!(out, "  }}")?;
        }
    }
    writeln!(out, "}}")
}

/// The modifiers a block carries as a whole: the mask colour, or the
/// interior of a transparent block; empty or starting with a space.
fn block_modifiers(world: &World, key: complex::BlockId, id: u32, options: PovOptions) -> String {
    if options.mask {
        let [r, g, b] = mask_color(id);
        format!(" pigment {{ rgb <{r}/255, {g}/255, {b}/255> }} finish {{ ambient 1 diffuse 0 }}")
    } else if world.complex.block(key).is_transparent() {
        format!(" interior {{ ior {} }}", Num(world.block_material(key).ior))
    } else {
        String::new()
    }
}

/// `quadric { … matrix < … >` in the quadric's eigenframe (see the module
/// docs), without the closing brace.
fn write_quadric(out: &mut String, q: &Quadric) -> std::fmt::Result {
    let (c, a, w, k) = q.local_parts();
    let eig = SymmetricEigen::new(a);
    let r: Matrix3<f64> = eig.eigenvectors;
    let mut lambda = eig.eigenvalues;
    let mut lin = r.transpose() * w;
    let mut k = k;
    // Scale so the largest coefficient is 1: POV's absolute tolerances
    // then mean the same for a tiny sphere as for a large one.
    let scale = lambda.amax().max(lin.amax()).max(k.abs());
    if scale > 0.0 && scale.is_finite() {
        lambda /= scale;
        lin /= scale;
        k /= scale;
    }
    // Rounding noise in a zero eigenvalue would read as a (huge) bounded
    // axis; a true zero lets POV see the tube or plane it is.
    for x in lambda.iter_mut().chain(lin.iter_mut()) {
        if x.abs() < 1e-12 {
            *x = 0.0;
        }
    }
    // A complement (more negative than positive curvature) is written as
    // the ordinary solid plus `inverse`, which POV bounds correctly.
    let inverse = lambda.sum() < 0.0;
    if inverse {
        lambda = -lambda;
        lin = -lin;
        k = -k;
    }
    write!(
        out,
        "quadric {{ {}, <0, 0, 0>, {}, {} matrix <{}, {}, {}, {}, {}, {}, {}, {}, {}, {}, {}, {}>{}",
        v3(&lambda),
        v3(&(2.0 * lin)),
        Num(k),
        // POV's matrix maps row vectors: rows are the images of the basis
        // vectors (the columns of R), then the translation c.
        Num(r[(0, 0)]),
        Num(r[(1, 0)]),
        Num(r[(2, 0)]),
        Num(r[(0, 1)]),
        Num(r[(1, 1)]),
        Num(r[(2, 1)]),
        Num(r[(0, 2)]),
        Num(r[(1, 2)]),
        Num(r[(2, 2)]),
        Num(c.x),
        Num(c.y),
        Num(c.z),
        if inverse { " inverse" } else { "" }
    )
}

/// `plane { n/|n|, -d/|n| }` around the half-space's reference point `o`:
/// `n·(x − o) + d ≤ 0`; without the closing brace.
fn write_plane(out: &mut String, h: &HalfSpace) -> std::fmt::Result {
    let n = *h.normal_vector();
    let len = n.norm();
    let o: Point3<f64> = h.reference_point();
    let d = h.vector().w + n.dot(&o.coords);
    write!(out, "plane {{ {}, {}", v3(&(n / len)), Num(-d / len))?;
    if o.coords != Vector3::zeros() {
        write!(out, " translate {}", v3(&o.coords))?;
    }
    Ok(())
}

/// A POV texture approximating a material under the shading model of docs/model.md §5:
/// the pigment is the diffuse colour, POV's ambient is scaled so that
/// `pigment × ambient = Ma × Sa`, Phong or Blinn-Phong maps to `phong` or
/// `specular`, and `transmit` to the pigment's filter channel.
fn texture(m: &Material, scene_ambient: &[f64; 3]) -> String {
    let filter = m.transmit.max();
    let (pigment, diffuse) = if filter > 0.0 {
        // POV filters transmitted light by the pigment colour: colour
        // `kt/max(kt)` with filter `max(kt)` transmits `kt`. The diffuse
        // coefficient then carries the diffuse reflectance's brightness.
        let c = m.transmit / filter;
        (c, m.diffuse.mean() / c.mean())
    } else if m.diffuse.iter().any(|x| *x > 0.0) {
        (m.diffuse, 1.0)
    } else {
        (m.ambient, 0.0)
    };
    let want_ambient = m.ambient.component_mul(&Vector3::from(*scene_ambient));
    let ambient = Vector3::from_fn(|i, _| if pigment[i] > 0.0 { want_ambient[i] / pigment[i] } else { 0.0 });
    let mut t = format!(
        "pigment {{ rgbf <{}, {}, {}, {}> }} finish {{ ambient rgb {} diffuse {}",
        Num(pigment.x),
        Num(pigment.y),
        Num(pigment.z),
        Num(filter),
        v3(&ambient),
        Num(diffuse)
    );
    let spec = m.specular.max();
    if spec > 0.0 {
        match m.model {
            Model::Phong => {
                let _ = write!(t, " phong {} phong_size {}", Num(spec), Num(m.shininess));
            }
            Model::BlinnPhong => {
                let _ = write!(t, " specular {} roughness {}", Num(spec), Num(1.0 / m.shininess.max(1e-3)));
            }
        }
    }
    if m.reflect.iter().any(|x| *x > 0.0) {
        let _ = write!(t, " reflection {{ rgb {} }}", v3(&m.reflect));
    }
    t.push_str(" }");
    t
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn mask_colours_encode_ids() {
        for (id, want) in [(1, [1, 0, 0]), (255, [255, 0, 0]), (256, [0, 1, 0]), (100_000, [160, 134, 1])] {
            assert_eq!(mask_color(id), want, "{id}");
            let [r, g, b] = want.map(u32::from);
            assert_eq!(r + 256 * g + 65536 * b, id);
        }
    }

    #[test]
    fn orthographic_cameras_span_the_image_in_world_units() {
        // A 3-4-5 image: a diagonal of 5 world units is 4 wide and 3 high.
        let text = r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -2], "width": 40, "height": 30,
                                    "projection": "orthographic", "diagonal": 5 },
                        "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#;
        let world = crate::format::SceneFile::load_str(text).unwrap();
        let pov = export(&world, PovOptions::default()).unwrap();
        let camera = pov.split("camera {").nth(1).unwrap();
        assert!(camera.contains("orthographic"), "{camera}");
        assert!(camera.contains("direction <0, 0, -1>"), "{camera}");
        assert!(camera.contains("right <4, 0, 0>") && camera.contains("up <0, 3, 0>"), "{camera}");
    }

    #[test]
    fn numbers_never_use_exponents() {
        for x in [1e-20, 1e20, -3.5e-7, 0.0, -0.0, 1.0 / 3.0] {
            let s = Num(x).to_string();
            assert!(!s.contains('e'), "{s}");
            assert_eq!(s.parse::<f64>().unwrap(), if x == 0.0 { 0.0 } else { x });
        }
    }
}
