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
    let rows: Vec<(DVec3, DVec3)> = read_number_rows(
        path,
        "a motion path file",
        ["px", "py", "pz", "tx", "ty", "tz"],
        &format!("pose rows; a path has at most {MAX_PATH_ROWS} frames (motion.frames' limit)"),
    )?
    .map(|row| row.map(|(v, _)| (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]))))
    .collect::<Result<_>>()?;
    if rows.len() < 2 {
        return Err(Error::data_file(
            path,
            rows.len() + 1,
            format!("{} pose rows; a path needs at least 2 frames", rows.len()),
        ));
    }
    Ok(rows)
}

/// The rows of a CSV file of finite numbers under exactly the header `columns`, streamed: each
/// row's values and its 1-based line. Errors name the file and line: a wrong header, more than
/// [`MAX_PATH_ROWS`] rows ("more than N {too_many}"), a row of another length, a value that is
/// not a finite number (by its column). `what` names the file in the size check.
pub(crate) fn read_number_rows<const N: usize>(
    path: &Path,
    what: &'static str,
    columns: [&'static str; N],
    too_many: &str,
) -> Result<impl Iterator<Item = Result<([f64; N], usize)>> + use<N>> {
    let file = crate::config::open_bounded(path, MAX_PATH_FILE_BYTES, what)?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .from_reader(std::io::BufReader::new(file));
    let headers = reader.headers().map_err(|e| Error::data_file(path, 1, e.to_string()))?;
    if headers.iter().collect::<Vec<_>>() != columns {
        return Err(Error::data_file(
            path,
            1,
            format!(
                "header is {:?}; expected the columns {}",
                crate::config::clip_quote(&headers.iter().collect::<Vec<_>>().join(",")),
                columns.join(",")
            ),
        ));
    }
    let path = path.to_path_buf();
    let too_many = too_many.to_string();
    Ok(reader.into_records().enumerate().map(move |(i, record)| {
        let line = i + 2;
        if i >= MAX_PATH_ROWS {
            return Err(Error::data_file(
                &path,
                line,
                format!("more than {MAX_PATH_ROWS} {too_many}"),
            ));
        }
        let record = record.map_err(|e| Error::data_file(&path, line, e.to_string()))?;
        if record.len() != N {
            return Err(Error::data_file(
                &path,
                line,
                format!("{} values; expected {N} ({})", record.len(), columns.join(",")),
            ));
        }
        let mut v = [0.0; N];
        for (j, field) in record.iter().enumerate() {
            v[j] = field.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                Error::data_file(
                    &path,
                    line,
                    format!(
                        "column {} = {:?} is not a finite number",
                        columns[j],
                        crate::config::clip_quote(field)
                    ),
                )
            })?;
        }
        Ok((v, line))
    }))
}
