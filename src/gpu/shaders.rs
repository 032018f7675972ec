//! The WGSL sources, embedded in the binary. WGSL has no include: a pass that evaluates the field gets
//! `field_common.wgsl` (the source structs and distance functions) prepended, so they live in one place.

/// Shared structs and functions of the field.
pub const FIELD_COMMON: &str = include_str!("../../shaders/field_common.wgsl");
/// The field pass proper (without the common part).
pub const FIELD_PASS: &str = include_str!("../../shaders/field.wgsl");
/// The billboard pass.
pub const BILLBOARD_PASS: &str = include_str!("../../shaders/billboard.wgsl");

/// The smooth upsampling of the viewer's low-resolution preview field.
pub const UPSAMPLE_PASS: &str = include_str!("../../shaders/upsample.wgsl");

/// The running mean of jittered frames.
pub const AVERAGE_PASS: &str = include_str!("../../shaders/average.wgsl");

/// The viewer's ground grid.
pub const GRID_PASS: &str = include_str!("../../shaders/grid.wgsl");
/// The viewer's copy of its offscreen viewport into egui's frame.
pub const BLIT_PASS: &str = include_str!("../../shaders/blit.wgsl");

/// The complete source of the field pass's module.
pub fn field_module_source() -> String {
    format!("{FIELD_COMMON}\n{FIELD_PASS}")
}

/// Every shader module the program builds, by name: what the validation tests check.
pub fn all_modules() -> Vec<(&'static str, String)> {
    vec![
        ("field.wgsl (with field_common.wgsl)", field_module_source()),
        ("billboard.wgsl", BILLBOARD_PASS.to_string()),
        ("average.wgsl", AVERAGE_PASS.to_string()),
        ("upsample.wgsl", UPSAMPLE_PASS.to_string()),
        ("grid.wgsl", GRID_PASS.to_string()),
        ("blit.wgsl", BLIT_PASS.to_string()),
    ]
}
