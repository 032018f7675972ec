//! Writing images: PNG (8-bit sRGB-encoded display values) and OpenEXR (32-bit float), chosen by the output's
//! extension, always atomically: the image goes to a temporary file beside the destination, which is then
//! renamed over it, so an interrupted write leaves the previous file intact.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Image file formats the command line writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Exr,
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: unknown image extension {ext:?}: use .png or .exr for an image (name_####.png or name_####.exr for a sequence), or .gif, .mp4 or .webm for an animation", path.display())]
    UnknownExtension { path: PathBuf, ext: String },
    #[error("{}: the directory {} does not exist", path.display(), dir.display())]
    MissingDirectory { path: PathBuf, dir: PathBuf },
    #[error("{}: is a directory; give a file name such as out.png", path.display())]
    IsDirectory { path: PathBuf },
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: cannot encode the image: {source}", path.display())]
    Encode {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
}

impl OutputError {
    /// True when the user's request is at fault (exit status 2), false for failures of the machine.
    pub fn is_input_error(&self) -> bool {
        matches!(
            self,
            OutputError::UnknownExtension { .. }
                | OutputError::MissingDirectory { .. }
                | OutputError::IsDirectory { .. }
        )
    }
}

/// Checks a destination before any work: known extension, existing directory. Returns its format.
pub fn check_destination(path: &Path) -> Result<Format, OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsDirectory {
            path: path.to_owned(),
        });
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let format = match ext.as_str() {
        "png" => Format::Png,
        "exr" => Format::Exr,
        _ => {
            return Err(OutputError::UnknownExtension {
                path: path.to_owned(),
                ext: ext.to_string(),
            });
        }
    };
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(OutputError::MissingDirectory {
            path: path.to_owned(),
            dir: dir.to_owned(),
        });
    }
    Ok(format)
}

/// Checks that `path` could be written: not a directory, in a directory that exists (any extension).
pub fn check_directory(path: &Path) -> Result<(), OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsDirectory {
            path: path.to_owned(),
        });
    }
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(OutputError::MissingDirectory {
            path: path.to_owned(),
            dir: dir.to_owned(),
        });
    }
    Ok(())
}

/// The folder `path` is in (the working directory for a bare file name).
pub fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// How an image's alpha is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Alpha {
    /// No alpha channel: RGB.
    Opaque,
    /// Alpha with the color not multiplied by it (PNG's convention, and what most viewers expect of a PNG). An
    /// EXR is written associated all the same: that is the OpenEXR convention.
    Straight,
    /// Alpha with the color multiplied by it (associated), for engines' premultiplied blend modes.
    Premultiplied,
}

impl Alpha {
    /// The alpha of an export: opaque, or transparent straight or premultiplied.
    pub fn of(transparent: bool, premultiplied: bool) -> Alpha {
        match (transparent, premultiplied) {
            (false, _) => Alpha::Opaque,
            (true, false) => Alpha::Straight,
            (true, true) => Alpha::Premultiplied,
        }
    }
}

/// The chromaticities of the exported colors, stated in every EXR: sRGB's primaries (those of Rec. 709) and its
/// D65 white.
pub const SRGB_PRIMARIES: [[f32; 2]; 4] =
    [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06], [0.3127, 0.3290]];

/// What an EXR's values are, in its header (attribute `energywave:values`), and OpenImageIO's colour space
/// attribute (`oiio:ColorSpace`) to the same effect.
pub const EXR_VALUES_NOTE: &str = "display-referred: the viewer's colors and blend as they are (sRGB-encoded, \
     not linear), before the display's clamp: values above 1 kept (an opaque frame's blend, a transparent \
     one's associated color), below 0 set to 0; alpha associated; composite in this space, not in scene-linear";

/// Writes an RGBA image (rows from the top) as PNG (8-bit) or EXR (32-bit float) by the path's extension. With
/// an alpha the pixels are premultiplied (associated), as the transparent export makes them: a PNG gets them
/// straight or premultiplied as `alpha` says (clamped to [0, 1]), an EXR associated and unclamped (B > 1 keeps its
/// HDR color), with its color space stated (`SRGB_PRIMARIES`, `EXR_VALUES_NOTE`). Opaque: RGB, a PNG clamped.
pub fn write_rgba(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f64; 4]],
    alpha: Alpha,
) -> Result<(), OutputError> {
    let format = check_destination(path)?;
    if format == Format::Exr {
        let encoded = encode_exr(
            path,
            width,
            height,
            pixels,
            alpha != Alpha::Opaque,
            EXR_VALUES_NOTE,
        )?;
        return write_atomically(path, &encoded);
    }
    write_png8(
        path,
        width,
        height,
        &encode_rgba8(pixels, alpha),
        alpha != Alpha::Opaque,
    )
}

/// RGBA display values (premultiplied where transparent, as the transparent export makes them) to the 8-bit
/// RGBA a PNG, a GIF or a video frame holds, clamped to [0, 1] and rounded: the color straight or premultiplied
/// as `alpha` says, alpha 255 where opaque.
pub fn encode_rgba8(pixels: &[[f64; 4]], alpha: Alpha) -> Vec<u8> {
    pixels
        .iter()
        .flat_map(|&p| {
            let p = match alpha {
                Alpha::Opaque => [p[0], p[1], p[2], 1.0],
                Alpha::Straight if p[3] > 0.0 => [p[0] / p[3], p[1] / p[3], p[2] / p[3], p[3]],
                Alpha::Straight => [0.0; 4],
                Alpha::Premultiplied => p,
            };
            p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
        })
        .collect()
}

/// Writes 8-bit RGBA (rows from the top) as a PNG: RGBA with `alpha`, else RGB (the alpha bytes dropped).
pub fn write_png8(
    path: &Path,
    width: u32,
    height: u32,
    rgba: &[u8],
    alpha: bool,
) -> Result<(), OutputError> {
    let img = if alpha {
        image::DynamicImage::ImageRgba8(
            image::RgbaImage::from_raw(width, height, rgba.to_vec()).expect("size matches"),
        )
    } else {
        let rgb = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        image::DynamicImage::ImageRgb8(
            image::RgbImage::from_raw(width, height, rgb).expect("size matches"),
        )
    };
    let encoded = encode(path, img, image::ImageFormat::Png)?;
    write_atomically(path, &encoded)
}

/// What the values of a brightness EXR are (`render --brightness`), in its header.
pub const EXR_BRIGHTNESS_NOTE: &str = "the billboard's brightness B (R = G = B), W x W texels, rows from the top, \
     before the blend and unclamped";

/// An EXR of `pixels` (f32, lossless ZIP), RGBA when `alpha`, with the header's chromaticities and `note` on its
/// values. Its chunks go in increasing line order, so the same pixels give the same bytes whatever order the
/// writer's threads compress them in (the `image` crate's EXR writer leaves the order to them).
fn encode_exr(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f64; 4]],
    alpha: bool,
    note: &str,
) -> Result<Vec<u8>, OutputError> {
    use exr::meta::attribute::{AttributeValue, Chromaticities, Text};
    use exr::prelude::*;
    let (w, h) = (width as usize, height as usize);
    let at = |p: Vec2<usize>| pixels[p.y() * w + p.x()].map(|c| c as f32);
    let mut attributes = LayerAttributes::named("");
    attributes.software_name = Some(Text::from("energywave"));
    attributes.other.insert(
        Text::from("energywave:values"),
        AttributeValue::Text(Text::from(note)),
    );
    let [r, g, b, white] = SRGB_PRIMARIES.map(|[x, y]| Vec2(x, y));
    let chromaticities = Some(Chromaticities {
        red: r,
        green: g,
        blue: b,
        white,
    });
    // Each map of further attributes holds one, the layer's and the image's: the writer takes them in a hash map's
    // order, which differs from run to run, and two in one map made the same frame two different files.
    let color_space = (
        Text::from("oiio:ColorSpace"),
        AttributeValue::Text(Text::from("sRGB")),
    );
    let mut buf = std::io::Cursor::new(Vec::new());
    let failed = |e: exr::error::Error| OutputError::Encode {
        path: path.to_owned(),
        source: image::ImageError::Encoding(image::error::EncodingError::new(
            image::error::ImageFormatHint::Exact(image::ImageFormat::OpenExr),
            e,
        )),
    };
    if alpha {
        let layer = Layer::new(
            (w, h),
            attributes,
            Encoding::SMALL_LOSSLESS,
            SpecificChannels::rgba(|p| {
                let [r, g, b, a] = at(p);
                (r, g, b, a)
            }),
        );
        let mut image = Image::from_layer(layer);
        image.attributes.chromaticities = chromaticities;
        image
            .attributes
            .other
            .insert(color_space.0.clone(), color_space.1.clone());
        image.write().to_buffered(&mut buf).map_err(failed)?;
    } else {
        let layer = Layer::new(
            (w, h),
            attributes,
            Encoding::SMALL_LOSSLESS,
            SpecificChannels::rgb(|p| {
                let [r, g, b, _] = at(p);
                (r, g, b)
            }),
        );
        let mut image = Image::from_layer(layer);
        image.attributes.chromaticities = chromaticities;
        image
            .attributes
            .other
            .insert(color_space.0.clone(), color_space.1.clone());
        image.write().to_buffered(&mut buf).map_err(failed)?;
    }
    Ok(buf.into_inner())
}

/// Writes a `w` x `w` field of unclamped floats (the brightness B) as a float EXR with R = G = B = value.
pub fn write_brightness_exr(path: &Path, w: u32, values: &[f64]) -> Result<(), OutputError> {
    let pixels: Vec<[f64; 4]> = values.iter().map(|&b| [b, b, b, 1.0]).collect();
    let encoded = encode_exr(path, w, w, &pixels, false, EXR_BRIGHTNESS_NOTE)?;
    write_atomically(path, &encoded)
}

fn encode(
    path: &Path,
    img: image::DynamicImage,
    format: image::ImageFormat,
) -> Result<Vec<u8>, OutputError> {
    let mut buf = std::io::Cursor::new(Vec::new());
    img.write_to(&mut buf, format)
        .map_err(|source| OutputError::Encode {
            path: path.to_owned(),
            source,
        })?;
    Ok(buf.into_inner())
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io = |source| OutputError::Io {
        path: path.to_owned(),
        source,
    };
    let dir = parent_dir(path);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}
