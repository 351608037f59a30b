//! Results streamed to a file as they are computed, instead of held in memory.
//!
//! A run given a [`RowSink`] ([`Sink::Stream`](crate::Sink::Stream) in its
//! [`RunOptions`](crate::RunOptions)) sends it its rows in chunks of about [`CHUNK_BYTES`]: its
//! analysis hands each full chunk of its [`Results`] to the sink, and only the chunk being filled
//! is in memory. The run's summary is the same as without a sink: the reaction peaks are kept as
//! the rows go by, and `output_points` counts the rows written.
//!
//! [`CsvSink`] writes `results.csv` exactly as [`Results::write_csv`](super::Results::write_csv)
//! does (the same bytes); the Python package adds Parquet through the same trait.

use super::Results;
use crate::error::Error;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Bytes of output values held before a chunk goes to the sink: 16 MiB. Large enough that a
/// sink's per-call cost (a Parquet row group, a Python call) is spread over many rows of a small
/// mechanism (29,000 rows of the loaded quick-return's 71 columns and time), small against the
/// memory of a large one (11 rows of a 10,000-body chain's 180,009 columns, beside its 350 MB
/// of solver state).
pub const CHUNK_BYTES: usize = 16 << 20;

/// Where the rows of a streamed run go (`Sync`, as the results that keep it may be shared).
pub trait RowSink: Send + Sync {
    /// Before the first chunk: the names of the columns after `time`.
    fn begin(&mut self, names: &[String]) -> std::io::Result<()>;
    /// A chunk of rows: their times, and each column's values at them.
    fn write(&mut self, time: &[f64], columns: &[Vec<f64>]) -> std::io::Result<()>;
    /// After the last chunk (also after a failed run, whose rows up to the failure were written).
    fn finish(&mut self) -> std::io::Result<()>;
    /// The file written, for error messages.
    fn path(&self) -> String;
    /// Bytes of output values to hold before a chunk is written.
    fn chunk_bytes(&self) -> usize {
        CHUNK_BYTES
    }
}

/// `results.csv` written as the rows come: a header, then one line per output time, numbers in
/// the shortest form that reads back to the same double. The file is made when the run begins
/// to write it, not before: its header is written under a temporary name beside it, which then
/// replaces any file at `path` (never truncated in place). Each chunk of rows is then one write,
/// flushed: a process killed between chunks leaves whole lines, and one killed during a write
/// leaves at most one line cut short, without its line end (`linkwork.stream.read` drops it).
pub struct CsvSink {
    path: PathBuf,
    out: Option<File>,
}

impl CsvSink {
    /// A sink for the file at `path`.
    pub fn at(path: &Path) -> CsvSink {
        CsvSink { path: path.to_path_buf(), out: None }
    }

    /// Write `lines` (whole lines) at the end of the file in one call.
    fn append(&mut self, lines: &[u8]) -> std::io::Result<()> {
        match &mut self.out {
            Some(out) => out.write_all(lines),
            None => Err(std::io::Error::other("the header was not written")),
        }
    }
}

/// The header line of `results.csv`.
pub(crate) fn write_header(w: &mut impl Write, names: &[String]) -> std::io::Result<()> {
    write!(w, "time")?;
    for n in names {
        write!(w, ",{n}")?;
    }
    writeln!(w)
}

/// The lines of `results.csv` for rows of `time` and `columns`.
pub(crate) fn write_rows(w: &mut impl Write, time: &[f64], columns: &[impl AsRef<[f64]>]) -> std::io::Result<()> {
    for (r, t) in time.iter().enumerate() {
        write!(w, "{t:?}")?;
        for c in columns {
            write!(w, ",{:?}", c.as_ref()[r])?;
        }
        writeln!(w)?;
    }
    Ok(())
}

impl RowSink for CsvSink {
    fn begin(&mut self, names: &[String]) -> std::io::Result<()> {
        let name = self.path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
        let temp = self.path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
        let mut header = Vec::new();
        write_header(&mut header, names)?;
        let made = File::create(&temp)
            .and_then(|mut f| f.write_all(&header))
            .and_then(|()| std::fs::rename(&temp, &self.path));
        if made.is_err() {
            let _ = std::fs::remove_file(&temp);
        }
        made?;
        self.out = Some(std::fs::OpenOptions::new().append(true).open(&self.path)?);
        Ok(())
    }

    fn write(&mut self, time: &[f64], columns: &[Vec<f64>]) -> std::io::Result<()> {
        let mut lines = Vec::new();
        write_rows(&mut lines, time, columns)?;
        self.append(&lines)
    }

    fn finish(&mut self) -> std::io::Result<()> {
        match &self.out {
            Some(out) => out.sync_all(),
            None => Ok(()),
        }
    }

    fn path(&self) -> String {
        self.path.display().to_string()
    }
}

/// A sink being written by one run: its header goes before the first chunk.
pub(crate) struct Stream<'a> {
    sink: &'a mut dyn RowSink,
    begun: bool,
}

impl std::fmt::Debug for Stream<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stream").field("path", &self.sink.path()).field("begun", &self.begun).finish()
    }
}

impl<'a> Stream<'a> {
    /// The run's writer of `sink`, nothing written yet.
    pub(crate) fn new(sink: &'a mut dyn RowSink) -> Stream<'a> {
        Stream { sink, begun: false }
    }

    /// Bytes of output values the sink takes a chunk ([`RowSink::chunk_bytes`]).
    pub(crate) fn chunk_bytes(&self) -> usize {
        self.sink.chunk_bytes()
    }

    fn io(&self, e: std::io::Error) -> Error {
        Error::Io { path: self.sink.path(), message: e.to_string() }
    }

    /// Give the sink the rows `results` holds (its header first), and empty them.
    pub(crate) fn flush(&mut self, results: &mut Results) -> Result<(), Error> {
        if !self.begun {
            self.begun = true;
            self.sink.begin(&results.names).map_err(|e| self.io(e))?;
        }
        if !results.time.is_empty() {
            self.sink.write(&results.time, &results.columns).map_err(|e| self.io(e))?;
            results.rows_sent();
        }
        Ok(())
    }

    /// The end of the run whose results are `results`: the rows still held go to the sink
    /// (after its header, which a run that failed before its first output point has not
    /// written), and the sink is finished.
    pub(crate) fn finish(mut self, results: &mut Results) -> Result<(), Error> {
        if !results.is_streamed() {
            results.stream_in_chunks(self.chunk_bytes());
        }
        results.select();
        // The sink is finished even when the last rows could not be written (a Parquet file
        // then still gets its footer, and holds the rows before).
        let flushed = self.flush(results);
        let finished = self.sink.finish().map_err(|e| self.io(e));
        flushed.and(finished)
    }
}
