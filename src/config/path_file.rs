//! Camera path files: the poses of `motion.path = "file"`.

use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};

/// At most this many pose rows (the `motion.frames` limit), counted as the file streams.
pub(crate) const MAX_PATH_ROWS: usize = 1_000_000;
/// A path file larger than this is refused before it is read (a 10⁶-row file of long numbers
/// is well under it).
pub(crate) const MAX_PATH_FILE_BYTES: u64 = 256 << 20;

/// Reads a camera path CSV: a header `px,py,pz,tx,ty,tz` and one row per frame
/// (camera position, then the point it looks at). At least two rows.
pub fn read_path_file(path: &Path) -> Result<Vec<(DVec3, DVec3)>> {
    let rows = read_path_rows(path)?;
    if rows.len() < 2 {
        return Err(Error::data_file(
            path,
            rows.len() + 1,
            format!("{} pose rows; a path needs at least 2 frames", rows.len()),
        ));
    }
    Ok(rows)
}

/// The rows of a camera path CSV as [`read_path_file`] reads them, however many (none too).
pub(crate) fn read_path_rows(path: &Path) -> Result<Vec<(DVec3, DVec3)>> {
    let file = crate::config::open_bounded(path, MAX_PATH_FILE_BYTES, "a motion path file")?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(std::io::BufReader::new(file));
    let expected = ["px", "py", "pz", "tx", "ty", "tz"];
    let headers = reader.headers().map_err(|e| Error::data_file(path, 1, e.to_string()))?;
    if headers.iter().collect::<Vec<_>>() != expected {
        return Err(Error::data_file(
            path,
            1,
            format!(
                "header is {:?}; expected the columns px,py,pz,tx,ty,tz",
                crate::config::clip_quote(&headers.iter().collect::<Vec<_>>().join(","))
            ),
        ));
    }
    let mut rows = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let line = i + 2;
        if i >= MAX_PATH_ROWS {
            return Err(Error::data_file(
                path,
                line,
                format!("more than {MAX_PATH_ROWS} pose rows; a path has at most {MAX_PATH_ROWS} frames (motion.frames' limit)"),
            ));
        }
        let record = record.map_err(|e| Error::data_file(path, line, e.to_string()))?;
        if record.len() != 6 {
            return Err(Error::data_file(
                path,
                line,
                format!("{} values; expected 6 (px,py,pz,tx,ty,tz)", record.len()),
            ));
        }
        let mut v = [0.0; 6];
        for (j, field) in record.iter().enumerate() {
            v[j] = field.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                Error::data_file(
                    path,
                    line,
                    format!(
                        "column {} = {:?} is not a finite number",
                        expected[j],
                        crate::config::clip_quote(field)
                    ),
                )
            })?;
        }
        rows.push((DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5])));
    }
    Ok(rows)
}
