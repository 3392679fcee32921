//! `[surface]`: what colours the ground: the natural surface types, a colour ramp by height, or
//! the user's imagery.

use crate::surface::ColorRamp;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

crate::names::named_enum! {
    /// How the ground is coloured (`surface.style`).
    pub enum Style ("surface style") {
        /// Surface types from what the ground is: slope, height above the land around, hollows
        /// and crests, aspect, the water, the tree line and the snow line (docs/picture.md).
        Natural = "natural",
        /// A colour ramp by height, in gdaldem `color-relief`'s format (`surface.color_ramp`).
        Ramp = "ramp",
        /// The user's imagery (`surface.image`) where it covers, the natural surface elsewhere.
        Image = "image",
    }
}

/// `[surface]`: the ground's colour, lit by the same sun, sky and air whichever it is.
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SurfaceSection {
    /// `natural`, `ramp` or `image`; without it, `image` where `image` is given, else `ramp`
    /// where `color_ramp` is, else `natural`.
    pub style: Option<Style>,
    /// Imagery draped over the ground: an RGB, RGBA or grey GeoTIFF (or COG), a PNG or JPEG
    /// with a world file, or an image pyramid's folder (`terrain tiles`), relative to the scene
    /// file, placed by its georeference.
    pub image: Option<PathBuf>,
    /// A colour ramp file in gdaldem `color-relief`'s text format, relative to the scene file, or
    /// a built-in ramp's name (`hypsometric`, `viridis`); without it, `ramp` uses `hypsometric`.
    pub color_ramp: Option<PathBuf>,
}

impl SurfaceSection {
    /// The style in force: the key, else `image` where an image is given, else `ramp` where a
    /// ramp is, else `natural`.
    pub fn style(&self) -> Style {
        match (self.style, &self.image, &self.color_ramp) {
            (Some(s), _, _) => s,
            (None, Some(_), _) => Style::Image,
            (None, None, Some(_)) => Style::Ramp,
            (None, None, None) => Style::Natural,
        }
    }
}

impl super::Scene {
    /// The colour ramp the ground is drawn with, read from its file (relative to the scene's
    /// folder) or built in; `None` for the natural surface.
    pub fn color_ramp(&self) -> crate::Result<Option<ColorRamp>> {
        if self.surface.style() != Style::Ramp {
            return Ok(None);
        }
        let Some(path) = &self.surface.color_ramp else {
            return Ok(ColorRamp::built_in("hypsometric"));
        };
        let built_in = path.to_str().and_then(ColorRamp::built_in);
        match built_in {
            Some(ramp) => Ok(Some(ramp)),
            None => ColorRamp::load(&self.resolve(path)).map(Some),
        }
    }

    /// The user's imagery resampled onto `atlas`'s grid, with `surface.style = "image"`.
    pub fn drape(
        &self,
        atlas: &crate::sketch::Atlas,
    ) -> crate::Result<Option<crate::surface::Drape>> {
        match (&self.surface.image, self.surface.style()) {
            (Some(path), Style::Image) => {
                crate::surface::drape(&self.resolve(path), atlas).map(Some)
            }
            _ => Ok(None),
        }
    }
}
