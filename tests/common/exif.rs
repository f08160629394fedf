//! Writing EXIF fields into JPEG files for tests (`kamadak-exif`'s writer).

/// `jpeg` (the bytes of a JPEG file) with the EXIF `fields` in an APP1 segment after its
/// start-of-image marker.
pub fn insert_exif(jpeg: &[u8], fields: &[exif::Field]) -> Vec<u8> {
    let mut w = exif::experimental::Writer::new();
    for f in fields {
        w.push_field(f);
    }
    let mut blob = std::io::Cursor::new(Vec::new());
    w.write(&mut blob, false).unwrap();
    let blob = blob.into_inner();
    let mut out = jpeg[..2].to_vec();
    out.extend([0xFF, 0xE1]);
    out.extend(((blob.len() + 8) as u16).to_be_bytes());
    out.extend(b"Exif\0\0");
    out.extend(&blob);
    out.extend(&jpeg[2..]);
    out
}

/// A small JPEG with the EXIF `fields` in an APP1 segment.
pub fn jpeg_with_exif(path: &std::path::Path, fields: &[exif::Field]) {
    let mut jpeg = Vec::new();
    image::RgbImage::new(8, 8)
        .write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
    std::fs::write(path, insert_exif(&jpeg, fields)).unwrap();
}

/// A field of the primary IFD.
pub fn exif_field(tag: exif::Tag, value: exif::Value) -> exif::Field {
    exif::Field {
        tag,
        ifd_num: exif::In::PRIMARY,
        value,
    }
}

/// Rationals `num/denom`.
pub fn rationals(v: &[(u32, u32)]) -> exif::Value {
    exif::Value::Rational(
        v.iter()
            .map(|&(num, denom)| exif::Rational { num, denom })
            .collect(),
    )
}

/// An ASCII value.
pub fn ascii(s: &str) -> exif::Value {
    exif::Value::Ascii(vec![s.as_bytes().to_vec()])
}
