//! Ground control point files: world points with the pixels where a photo shows them.
//!
//! Two formats, told apart by their first data line:
//! - **ImGRAFT text** (as `gcp8902.txt` of the Engabreen demo): one GCP per line,
//!   `X Y Z U V` separated by blanks or commas, `%` or `#` starts a comment, pixels
//!   MATLAB 1-based (the centre of the top-left pixel is (1, 1)); a number may be written
//!   as a sum or difference such as `1951+9` (ImGRAFT's files record offsets that way; the
//!   value is the sum). Further columns are ignored.
//! - **CSV with a header** naming the columns `x,y,z,u,v` and optionally `name` and
//!   `weight` (any order, case-insensitive); pixels 0-based by default (cliffmap's
//!   convention: the centre of the top-left pixel is (0, 0)).
//!
//! [`Gcp::pixel`] is always 0-based pixel-centre. Errors name the file and the line.

use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};

/// One ground control point.
#[derive(Clone, Debug, PartialEq)]
pub struct Gcp {
    /// Name (from the CSV's `name` column, else `"line N"`).
    pub name: String,
    /// World position, metres (the camera's frame: x east, y north, z up).
    pub world: DVec3,
    /// Observed pixel `[u, v]`, 0-based pixel-centre convention, u right, v down.
    pub pixel: [f64; 2],
    /// Relative weight of the point in the fit (> 0; default 1).
    pub weight: f64,
}

/// The pixel convention of a GCP file's `u, v` columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelOrigin {
    /// The format's own convention (ImGRAFT text: 1-based, CSV: 0-based).
    Format,
    /// 0-based: the centre of the top-left pixel is (0, 0).
    Zero,
    /// 1-based (MATLAB): the centre of the top-left pixel is (1, 1).
    One,
}

/// RMS distance (pixels) between where `cam` puts the GCPs in front of it and their
/// pixels, and how many those are (weights ignored): how well a camera fits held-out GCPs.
/// `(NaN, 0)` when none is in front.
pub fn gcp_rmse_px(cam: &crate::camera::CameraModel, gcps: &[Gcp]) -> (f64, usize) {
    let (mut sum, mut n) = (0.0, 0usize);
    for g in gcps {
        if let Some(q) = cam.project(g.world) {
            sum += (q[0] - g.pixel[0]).powi(2) + (q[1] - g.pixel[1]).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        (f64::NAN, 0)
    } else {
        ((sum / n as f64).sqrt(), n)
    }
}

/// Reads a GCP file (either format, see the module docs (`src/register/gcp.rs`)).
pub fn read_gcps(path: &Path, origin: PixelOrigin) -> Result<Vec<Gcp>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_gcps(&text, path, origin)
}

/// The column order an ImGRAFT-text GCP file was read in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GcpColumns {
    /// `X Y Z U V`, the documented order.
    WorldThenPixel,
    /// `U V X Y Z`, a common order of other tools.
    PixelThenWorld,
}

/// Reads a GCP file for a photo of `size` (width, height) pixels. A CSV names its columns;
/// for ImGRAFT text the order is detected when unambiguous: when the documented `X Y Z U V`
/// puts some pixels outside the image and `U V X Y Z` puts every one inside, the file is
/// read in the second order (returned, so that the caller can say so). When at most half of
/// the points fit the image in either order, an error names the file, the expected order
/// and the first line.
pub fn read_gcps_for_image(
    path: &Path,
    origin: PixelOrigin,
    size: (u32, u32),
) -> Result<(Vec<Gcp>, GcpColumns)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let gcps = parse_gcps(&text, path, origin)?;
    let first = text
        .lines()
        .map(|l| strip_comment(l).trim())
        .find(|l| !l.is_empty())
        .unwrap_or_default();
    let csv = is_csv_header(first);
    let inside = |gs: &[Gcp]| gs.iter().filter(|g| pixel_inside(g.pixel, size)).count();
    let n = gcps.len();
    let as_given = inside(&gcps);
    if as_given == n || csv {
        return Ok((gcps, GcpColumns::WorldThenPixel));
    }
    let one = origin != PixelOrigin::Zero;
    let swapped: Vec<Gcp> = gcps.iter().map(|g| pixel_first(g, one)).collect();
    let other = inside(&swapped);
    if other == n {
        return Ok((swapped, GcpColumns::PixelThenWorld));
    }
    if 2 * as_given > n {
        return Ok((gcps, GcpColumns::WorldThenPixel));
    }
    Err(Error::bad_input(
        path,
        format!(
            "the GCPs' pixels do not fit the {}x{} image in either column order (X Y Z U V: \
             {as_given} of {n} inside, U V X Y Z: {other} of {n}); expected X Y Z U V (world \
             metres, then pixels, 1-based unless --pixel-origin 0), e.g. \
             \"446003.2 7396345.1 512.3 1960 1494\"; the first line is \"{first}\"",
            size.0, size.1
        ),
    ))
}

/// Whether a 0-based pixel lies in a `size` image (pixel edges, half a pixel out).
fn pixel_inside(p: [f64; 2], size: (u32, u32)) -> bool {
    (-0.5..=size.0 as f64 - 0.5).contains(&p[0]) && (-0.5..=size.1 as f64 - 0.5).contains(&p[1])
}

/// The GCP a line `A B C D E` read as `X Y Z U V` (`g`) gives when read as `U V X Y Z`
/// (`one`: 1-based pixels).
fn pixel_first(g: &Gcp, one: bool) -> Gcp {
    let shift = if one { 1.0 } else { 0.0 };
    let v = [
        g.world.x,
        g.world.y,
        g.world.z,
        g.pixel[0] + shift,
        g.pixel[1] + shift,
    ];
    Gcp {
        name: g.name.clone(),
        world: DVec3::new(v[2], v[3], v[4]),
        pixel: to_zero_based([v[0], v[1]], one),
        weight: g.weight,
    }
}

/// Parses the text of a GCP file; `path` only names it in errors.
pub fn parse_gcps(text: &str, path: &Path, origin: PixelOrigin) -> Result<Vec<Gcp>> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, strip_comment(l).trim()))
        .filter(|(_, l)| !l.is_empty())
        .collect();
    let Some(&(_, first)) = lines.first() else {
        return Err(Error::bad_input(
            path,
            "no ground control points in the file",
        ));
    };
    let gcps = if is_csv_header(first) {
        parse_csv(&lines, path, origin)?
    } else {
        parse_imgraft(&lines, path, origin)?
    };
    if gcps.is_empty() {
        return Err(Error::bad_input(
            path,
            "no ground control points in the file",
        ));
    }
    Ok(gcps)
}

/// Whether the first data line is a CSV header (letters, commas, not all numbers).
fn is_csv_header(first: &str) -> bool {
    first.chars().any(|c| c.is_ascii_alphabetic()) && first.contains(',') && !looks_numeric(first)
}

fn strip_comment(line: &str) -> &str {
    let cut = line.find(['%', '#']).unwrap_or(line.len());
    &line[..cut]
}

/// Whether every field of a line parses as a number (a data line, not a header).
fn looks_numeric(line: &str) -> bool {
    line.split([',', ' ', '\t', ';'])
        .filter(|t| !t.is_empty())
        .all(|t| number(t).is_some())
}

/// A number, or a sum / difference of numbers such as `1951+9` or `12.5-0.5` (signs of
/// exponents stay with their number: `1e+3` is 1000).
fn number(token: &str) -> Option<f64> {
    let t = token.trim();
    if t.is_empty() {
        return None;
    }
    let b = t.as_bytes();
    let mut total = 0.0;
    let mut start = 0;
    for i in 1..=b.len() {
        let split = i == b.len()
            || ((b[i] == b'+' || b[i] == b'-') && !matches!(b[i - 1], b'e' | b'E' | b'+' | b'-'));
        if split {
            let part = &t[start..i];
            let v: f64 = part.parse().ok()?;
            if !v.is_finite() {
                return None;
            }
            total += v;
            start = i;
        }
    }
    Some(total)
}

fn to_zero_based(p: [f64; 2], one_based: bool) -> [f64; 2] {
    if one_based {
        [p[0] - 1.0, p[1] - 1.0]
    } else {
        p
    }
}

fn parse_imgraft(lines: &[(usize, &str)], path: &Path, origin: PixelOrigin) -> Result<Vec<Gcp>> {
    let one = origin != PixelOrigin::Zero;
    let mut out = Vec::new();
    for &(n, line) in lines {
        let tokens: Vec<&str> = line
            .split([',', ' ', '\t', ';'])
            .filter(|t| !t.is_empty())
            .collect();
        if tokens.len() < 5 {
            return Err(Error::bad_input(
                path,
                format!("line {n}: expected X Y Z U V, got {} fields", tokens.len()),
            ));
        }
        let mut v = [0.0; 5];
        for (k, t) in tokens[..5].iter().enumerate() {
            v[k] = number(t).ok_or_else(|| {
                Error::bad_input(path, format!("line {n}: \"{t}\" is not a number"))
            })?;
        }
        out.push(Gcp {
            name: format!("line {n}"),
            world: DVec3::new(v[0], v[1], v[2]),
            pixel: to_zero_based([v[3], v[4]], one),
            weight: 1.0,
        });
    }
    Ok(out)
}

fn parse_csv(lines: &[(usize, &str)], path: &Path, origin: PixelOrigin) -> Result<Vec<Gcp>> {
    let one = origin == PixelOrigin::One;
    let (hn, header) = lines[0];
    let names: Vec<String> = header
        .split(',')
        .map(|s| s.trim().to_ascii_lowercase())
        .collect();
    let col = |want: &str| names.iter().position(|n| n == want);
    let mut idx = [0usize; 5];
    for (k, want) in ["x", "y", "z", "u", "v"].iter().enumerate() {
        idx[k] = col(want).ok_or_else(|| {
            Error::bad_input(
                path,
                format!("line {hn}: the CSV header needs columns x,y,z,u,v (got \"{header}\")"),
            )
        })?;
    }
    let (name_col, weight_col) = (col("name"), col("weight"));
    let mut out = Vec::new();
    for &(n, line) in &lines[1..] {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let field = |k: usize| fields.get(k).copied().unwrap_or("");
        let mut v = [0.0; 5];
        for (k, &c) in idx.iter().enumerate() {
            let t = field(c);
            v[k] = number(t).ok_or_else(|| {
                Error::bad_input(
                    path,
                    format!("line {n}: column {} \"{t}\" is not a number", names[c]),
                )
            })?;
        }
        let weight = match weight_col {
            Some(c) if !field(c).is_empty() => {
                let w = number(field(c)).filter(|w| *w > 0.0);
                w.ok_or_else(|| {
                    Error::bad_input(
                        path,
                        format!(
                            "line {n}: weight \"{}\" must be a positive number",
                            field(c)
                        ),
                    )
                })?
            }
            _ => 1.0,
        };
        let name = name_col
            .map(field)
            .filter(|s| !s.is_empty())
            .map_or_else(|| format!("line {n}"), str::to_string);
        out.push(Gcp {
            name,
            world: DVec3::new(v[0], v[1], v[2]),
            pixel: to_zero_based([v[3], v[4]], one),
            weight,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gcp_rmse_counts_the_points_in_front_and_their_pixel_errors() {
        let r = crate::camera::rotation_from_yaw_pitch_roll(0.3, -0.1, 0.0);
        let cam =
            crate::camera::CameraModel::with_fov(DVec3::new(10.0, 20.0, 30.0), r, 800, 600, 1.0);
        let ray = |u: f64, v: f64| cam.pixel_ray(u, v).unwrap();
        let gcp = |world: DVec3, pixel: [f64; 2]| Gcp {
            name: String::new(),
            world,
            pixel,
            weight: 1.0,
        };
        // two points seen where their pixels say, off by 3 and 4 px; one behind the camera
        let gcps = [
            gcp(cam.position + ray(100.0, 200.0) * 50.0, [103.0, 200.0]),
            gcp(cam.position + ray(600.0, 400.0) * 80.0, [600.0, 404.0]),
            gcp(cam.position - ray(400.0, 300.0) * 20.0, [400.0, 300.0]),
        ];
        let (rmse, n) = gcp_rmse_px(&cam, &gcps);
        assert_eq!(n, 2);
        assert!((rmse - 12.5f64.sqrt()).abs() < 1e-6, "{rmse}");
        assert!(gcp_rmse_px(&cam, &gcps[2..]).0.is_nan());
    }

    #[test]
    fn imgraft_text_with_sums_and_comments() {
        let text = "% Ground control points\n% X,Y,Z U,V\n  445562 7395662 596.4 1951+9 1490+4 \n445359.2, 7396092.5, 519.2, 3851, 1889 % note\n";
        let g = parse_gcps(text, Path::new("g.txt"), PixelOrigin::Format).unwrap();
        assert_eq!(g.len(), 2);
        assert_eq!(g[0].world, DVec3::new(445562.0, 7395662.0, 596.4));
        assert_eq!(g[0].pixel, [1959.0, 1493.0]); // 1960, 1494 in 1-based pixels
        assert_eq!(g[1].pixel, [3850.0, 1888.0]);
        assert_eq!(g[0].name, "line 3");
        let zero = parse_gcps(text, Path::new("g.txt"), PixelOrigin::Zero).unwrap();
        assert_eq!(zero[0].pixel, [1960.0, 1494.0]);
    }

    #[test]
    fn csv_with_header_names_and_weights() {
        let text = "name,x,y,z,u,v,weight\nrock,1,2,3,10.5,20,2\n,4,5,6,7,8,\n";
        let g = parse_gcps(text, Path::new("g.csv"), PixelOrigin::Format).unwrap();
        assert_eq!(g.len(), 2);
        assert_eq!(
            (g[0].name.as_str(), g[0].pixel, g[0].weight),
            ("rock", [10.5, 20.0], 2.0)
        );
        assert_eq!(
            (g[1].name.as_str(), g[1].world, g[1].weight),
            ("line 3", DVec3::new(4.0, 5.0, 6.0), 1.0)
        );
        let one = parse_gcps(text, Path::new("g.csv"), PixelOrigin::One).unwrap();
        assert_eq!(one[0].pixel, [9.5, 19.0]);
    }

    #[test]
    fn numbers_sums_and_exponents() {
        assert_eq!(number("1951+9"), Some(1960.0));
        assert_eq!(number("-3.5"), Some(-3.5));
        assert_eq!(number("12.5-0.5"), Some(12.0));
        assert_eq!(number("1e+3"), Some(1000.0));
        assert_eq!(number("2E-1+1"), Some(1.2));
        assert_eq!(number("abc"), None);
        assert_eq!(number("1+"), None);
        assert_eq!(number("nan"), None);
    }

    #[test]
    fn pixel_first_files_are_read_in_their_order_and_misfits_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.txt");
        let world_first = "446003.2 7396345.1 512.3 1960 1494\n446100 7396400 600 120 30\n";
        std::fs::write(&p, world_first).unwrap();
        let (a, order) = read_gcps_for_image(&p, PixelOrigin::Format, (4290, 2856)).unwrap();
        assert_eq!(order, GcpColumns::WorldThenPixel);
        let pixel_first = "1960 1494 446003.2 7396345.1 512.3\n120 30 446100 7396400 600\n";
        std::fs::write(&p, pixel_first).unwrap();
        let (b, order) = read_gcps_for_image(&p, PixelOrigin::Format, (4290, 2856)).unwrap();
        assert_eq!(order, GcpColumns::PixelThenWorld);
        assert_eq!(a, b);
        // pixels that fit neither order: an error with the expected order and the line
        std::fs::write(
            &p,
            "446003 7396345 512 9000 9000\n446100 7396400 600 9100 9100\n",
        )
        .unwrap();
        let e = read_gcps_for_image(&p, PixelOrigin::Format, (4290, 2856))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("g.txt")
                && e.contains("X Y Z U V")
                && e.contains("\"446003 7396345 512 9000 9000\""),
            "{e}"
        );
    }

    #[test]
    fn bad_files_name_the_line() {
        for (text, want) in [
            ("", "no ground control points"),
            ("% only comments\n", "no ground control points"),
            ("1 2 3 4\n", "line 1: expected X Y Z U V"),
            ("1 2 3 4 x5\n", "line 1: \"x5\" is not a number"),
            ("x,y,z,u\n1,2,3,4\n", "needs columns x,y,z,u,v"),
            ("x,y,z,u,v\n1,2,3,4,oops\n", "line 2: column v"),
            ("x,y,z,u,v,weight\n1,2,3,4,5,-1\n", "line 2: weight"),
        ] {
            let e = parse_gcps(text, Path::new("bad.txt"), PixelOrigin::Format)
                .unwrap_err()
                .to_string();
            assert!(e.contains("bad.txt") && e.contains(want), "{text:?}: {e}");
        }
    }
}
