//! Command-line values of library enums: each mirrors a library type (same values, same
//! help per value) so that `clap` stays out of the library.

use cliffmap::DemFormat;
use cliffmap::fsutil::PngCompression;

/// On-disk DEM formats cliffmap reads ([`DemFormat`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum DemFormatArg {
    /// GeoTIFF (or plain TIFF with explicit spacing/origin).
    Geotiff,
    /// 16-bit greyscale PNG; height = value * z_scale + z_offset.
    Png16,
    /// Mapbox Terrain-RGB PNG; height = -10000 + (R*65536 + G*256 + B) * 0.1.
    TerrainRgb,
    /// Raw little-endian f32, row-major, rows north to south; needs width and height.
    F32,
}

impl From<DemFormatArg> for DemFormat {
    fn from(a: DemFormatArg) -> DemFormat {
        match a {
            DemFormatArg::Geotiff => DemFormat::Geotiff,
            DemFormatArg::Png16 => DemFormat::Png16,
            DemFormatArg::TerrainRgb => DemFormat::TerrainRgb,
            DemFormatArg::F32 => DemFormat::F32,
        }
    }
}

/// PNG compression of store textures ([`PngCompression`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum PngCompressionArg {
    /// fdeflate with adaptive filtering: the fastest encoder, the `image` crate's default
    /// and what every store before the knob was written with. The default.
    #[default]
    Fast,
    /// A balanced zlib level: ~0.77× the size of `fast` at ~1/18 of its speed.
    Balanced,
    /// The strongest zlib level: the smallest files, slowest.
    Best,
}

impl From<PngCompressionArg> for PngCompression {
    fn from(a: PngCompressionArg) -> PngCompression {
        match a {
            PngCompressionArg::Fast => PngCompression::Fast,
            PngCompressionArg::Balanced => PngCompression::Balanced,
            PngCompressionArg::Best => PngCompression::Best,
        }
    }
}
