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
    #[error("{}: unknown image extension {ext:?}: use .png or .exr (or .gif for an animation)", path.display())]
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

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes an RGBA image (rows from the top, channels in [0, 1]) as PNG (8-bit) or EXR (32-bit float) by the
/// path's extension; `alpha` keeps the alpha channel, otherwise RGB is written.
pub fn write_rgba(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[f64; 4]],
    alpha: bool,
) -> Result<(), OutputError> {
    let format = check_destination(path)?;
    let channels = if alpha { 4 } else { 3 };
    let img = match format {
        Format::Png => {
            let bytes: Vec<u8> = pixels
                .iter()
                .flat_map(|p| {
                    p[..channels]
                        .iter()
                        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
                        .collect::<Vec<_>>()
                })
                .collect();
            if alpha {
                image::DynamicImage::ImageRgba8(
                    image::RgbaImage::from_raw(width, height, bytes).expect("size matches"),
                )
            } else {
                image::DynamicImage::ImageRgb8(
                    image::RgbImage::from_raw(width, height, bytes).expect("size matches"),
                )
            }
        }
        Format::Exr => {
            let floats: Vec<f32> = pixels
                .iter()
                .flat_map(|p| p[..channels].iter().map(|&c| c as f32).collect::<Vec<_>>())
                .collect();
            if alpha {
                image::DynamicImage::ImageRgba32F(
                    image::Rgba32FImage::from_raw(width, height, floats).expect("size matches"),
                )
            } else {
                image::DynamicImage::ImageRgb32F(
                    image::Rgb32FImage::from_raw(width, height, floats).expect("size matches"),
                )
            }
        }
    };
    let image_format = match format {
        Format::Png => image::ImageFormat::Png,
        Format::Exr => image::ImageFormat::OpenExr,
    };
    let encoded = encode(path, img, image_format)?;
    write_atomically(path, &encoded)
}

/// Writes a `w` x `w` field of unclamped floats (the brightness B) as a float EXR with R = G = B = value.
pub fn write_brightness_exr(path: &Path, w: u32, values: &[f64]) -> Result<(), OutputError> {
    let floats: Vec<f32> = values.iter().flat_map(|&b| [b as f32; 3]).collect();
    let img = image::DynamicImage::ImageRgb32F(
        image::Rgb32FImage::from_raw(w, w, floats).expect("size matches"),
    );
    let encoded = encode(path, img, image::ImageFormat::OpenExr)?;
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
