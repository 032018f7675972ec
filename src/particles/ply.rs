//! Particle sets from PLY point clouds, the format simulation and DCC tools write them in (ascii, binary of
//! either byte order; read by `ply-rs-bw`). Each `vertex` is a particle: `x`, `y`, `z` are required; `radius`
//! (or Houdini's `pscale`), `density` and a color (`red`, `green`, `blue`: 0..255 as integers, 0..1 as floats)
//! are read where present, the set's own values used where not.

use std::io::BufReader;
use std::path::Path;

use glam::DVec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{Encoding, Property, PropertyAccess, PropertyAccessResult};

use super::Particle;

/// The most particles a scene takes in all, from files and emitters together.
pub const MAX_PARTICLES: usize = 1_000_000;

/// The largest coordinate a position may have (the scene's `MAX_COORDINATE`): past it a value is taken for a
/// byte order misread.
pub const MAX_COORDINATE: f64 = 1e15;

/// What a particle takes from the set where its file gives nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Defaults {
    pub radius: f64,
    pub density: f64,
    pub color: [f64; 3],
}

/// One vertex as read, before it is checked.
#[derive(Default)]
struct Vertex {
    position: [Option<f64>; 3],
    radius: Option<f64>,
    density: Option<f64>,
    color: [Option<f64>; 3],
}

/// A color channel: integers are 0..255 (the PLY convention), floats 0..1.
fn channel(p: &Property) -> Option<f64> {
    match p {
        Property::Float(x) => Some(*x as f64),
        Property::Double(x) => Some(*x),
        other => other.to_f32_lossy().map(|x| x as f64 / 255.0),
    }
}

fn scalar(p: &Property) -> Option<f64> {
    match p {
        Property::Double(x) => Some(*x),
        other => other.to_f32_lossy().map(f64::from),
    }
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.position[0],
            "y" => &mut self.position[1],
            "z" => &mut self.position[2],
            "radius" | "pscale" => &mut self.radius,
            "density" => &mut self.density,
            "red" | "r" | "diffuse_red" => {
                self.color[0] = channel(&property);
                return PropertyAccessResult::Set;
            }
            "green" | "g" | "diffuse_green" => {
                self.color[1] = channel(&property);
                return PropertyAccessResult::Set;
            }
            "blue" | "b" | "diffuse_blue" => {
                self.color[2] = channel(&property);
                return PropertyAccessResult::Set;
            }
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = scalar(&property);
        PropertyAccessResult::Set
    }
}

/// Reads the particles of the PLY file at `path`; every problem a phrase to follow the file's name, naming the
/// vertex and the value where one is at fault.
pub fn read(path: &Path, defaults: Defaults) -> Result<Vec<Particle>, String> {
    let parser = Parser::<Vertex>::new();
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
    let mut reader = ply_rs_bw::parser::Reader::new(BufReader::new(file));
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| format!("not a PLY file this reads: {e}"))?;
    let Some(element) = header.elements.get("vertex") else {
        return Err("no vertex element: a particle set's particles are its vertices".to_owned());
    };
    for axis in ["x", "y", "z"] {
        if !element.properties.contains_key(axis) {
            return Err(format!(
                "its vertices have no {axis}: a particle's position is x, y, z"
            ));
        }
    }
    if element.count > MAX_PARTICLES {
        return Err(format!(
            "{} vertices: a scene takes at most {MAX_PARTICLES} particles",
            element.count
        ));
    }
    let payload = parser.read_payload(&mut reader, &header).map_err(|e| {
        format!(
            "cut short or damaged, its header promising {} vertices: {}",
            element.count,
            e.to_string().replace('\n', " ").replace('\t', "")
        )
    })?;
    let byte_order = match header.encoding {
        Encoding::Ascii => None,
        Encoding::BinaryBigEndian => Some("binary_big_endian"),
        Encoding::BinaryLittleEndian => Some("binary_little_endian"),
    };
    let vertices = payload.get("vertex").map(Vec::as_slice).unwrap_or(&[]);
    vertices
        .iter()
        .enumerate()
        .map(|(i, v)| particle(i, v, defaults, byte_order))
        .collect()
}

fn particle(
    i: usize,
    v: &Vertex,
    defaults: Defaults,
    byte_order: Option<&str>,
) -> Result<Particle, String> {
    let mut position = [0.0; 3];
    for (k, (slot, name)) in v.position.iter().zip(["x", "y", "z"]).enumerate() {
        let x = slot.ok_or_else(|| format!("vertex {i} has no {name}"))?;
        // A binary file read in the wrong byte order gives garbage: huge, not a number, or subnormal.
        let absurd = !x.is_finite()
            || x.abs() > MAX_COORDINATE
            || (x != 0.0 && x.abs() < f32::MIN_POSITIVE as f64);
        if absurd {
            let hint = byte_order.map_or(String::new(), |o| {
                format!(" (is the file's byte order right? its header says {o})")
            });
            return Err(format!(
                "vertex {i}: {name} = {x:e} is not a position{hint}"
            ));
        }
        position[k] = x;
    }
    let radius = v.radius.unwrap_or(defaults.radius);
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(format!("vertex {i}: radius {radius} must be positive"));
    }
    let density = v.density.unwrap_or(defaults.density);
    if !(density >= 0.0 && density.is_finite()) {
        return Err(format!("vertex {i}: density {density} must be at least 0"));
    }
    let mut color = defaults.color;
    for (c, given) in color.iter_mut().zip(v.color) {
        if let Some(x) = given {
            if !(0.0..=1.0).contains(&x) {
                return Err(format!(
                    "vertex {i}: a color channel of {x} is outside 0..1 (0..255 as integers)"
                ));
            }
            *c = x;
        }
    }
    Ok(Particle {
        position: DVec3::from_array(position),
        radius,
        density,
        color,
        emission: [1.0; 3],
    })
}
