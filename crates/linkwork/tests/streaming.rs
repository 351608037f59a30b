//! Results streamed to a file as they are computed (`Model::run` with a `Sink::Stream`): the file is the one a
//! run held in memory writes, byte for byte, whatever the chunks; the summary is the same; a
//! failed run's file has every row up to the failure; a file that cannot be written fails the
//! run naming it.

mod common;

use common::{example, pendulum_with_torque};
use linkwork::results::stream::{CsvSink, RowSink};
use linkwork::{Error, Model, RunOptions, Sink};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("linkwork-stream-{}-{name}", std::process::id()))
}

/// A run with its rows going to `sink`.
fn streaming(sink: Box<dyn RowSink>) -> RunOptions {
    RunOptions { sink: Sink::stream(sink), ..RunOptions::default() }
}

/// A [`CsvSink`] that writes a chunk every `rows_per_chunk` rows of `columns` columns, and
/// counts its chunks.
struct Chunked {
    csv: CsvSink,
    bytes: usize,
    chunks: Arc<Mutex<usize>>,
}

impl RowSink for Chunked {
    fn begin(&mut self, names: &[String]) -> std::io::Result<()> {
        self.csv.begin(names)
    }
    fn write(&mut self, time: &[f64], columns: &[Vec<f64>]) -> std::io::Result<()> {
        *self.chunks.lock().unwrap() += 1;
        self.csv.write(time, columns)
    }
    fn finish(&mut self) -> std::io::Result<()> {
        self.csv.finish()
    }
    fn path(&self) -> String {
        self.csv.path()
    }
    fn chunk_bytes(&self) -> usize {
        self.bytes
    }
}

/// Every analysis type of the quick-return (and the dynamic one with its reactions and efforts),
/// streamed whole and in chunks of 7 rows: the file and the summary are those of the run held in
/// memory, and the results returned hold no row but count them all.
#[test]
fn a_streamed_file_is_the_file_a_run_in_memory_writes() {
    let model = Model::load(example("quick_return_a.yaml")).unwrap();
    for analysis in ["kinematics", "dynamics_loaded", "inverse"] {
        let held = model.run(analysis, &Default::default()).unwrap();
        if analysis != "kinematics" {
            // The peaks kept as the rows go by are those of the columns: every joint's largest
            // resultant force.
            let peaks = &held.summary_json(None)["peaks"];
            for joint in &model.joints {
                let (fx, fy) = (held.column(&format!("{}.fx", joint.name)), held.column(&format!("{}.fy", joint.name)));
                let largest = fx.unwrap().iter().zip(fy.unwrap()).fold(0.0f64, |a, (x, y)| a.max(x.hypot(*y)));
                assert_eq!(peaks[format!("{}.force", joint.name)]["max_abs"].as_f64(), Some(largest), "{analysis}");
            }
        }
        let reference = temp(&format!("{analysis}-held.csv"));
        held.write_csv(&reference).unwrap();
        let expected = std::fs::read(&reference).unwrap();
        let columns = std::fs::read_to_string(&reference).unwrap().lines().next().unwrap().split(',').count();
        for rows_per_chunk in [None, Some(7)] {
            let path = temp(&format!("{analysis}-streamed.csv"));
            let chunks = Arc::new(Mutex::new(0));
            let bytes = rows_per_chunk.map_or(linkwork::results::stream::CHUNK_BYTES, |r| 8 * columns * r);
            let sink = Chunked { csv: CsvSink::at(&path), bytes, chunks: Arc::clone(&chunks) };
            let streamed = model.run(analysis, &streaming(Box::new(sink))).unwrap();
            assert!(std::fs::read(&path).unwrap() == expected, "{analysis} {rows_per_chunk:?}: the files differ");
            assert!(streamed.is_streamed() && streamed.time.is_empty(), "{analysis}: no row held");
            assert_eq!(streamed.len(), held.len());
            assert_eq!(streamed.summary_json(None), held.summary_json(None), "{analysis}");
            let want = rows_per_chunk.map_or(1, |r| held.len().div_ceil(r));
            assert_eq!(*chunks.lock().unwrap(), want, "{analysis} {rows_per_chunk:?}: chunks");
            std::fs::remove_file(&path).unwrap();
        }
        std::fs::remove_file(&reference).unwrap();
    }
}

/// A torque that is NaN past t = 0.503 s (tests/dynamics.rs): the streamed run fails as the run
/// in memory does, and its file has the same 51 rows, those up to 0.5 s.
#[test]
fn a_failed_streamed_run_keeps_its_rows() {
    let model = pendulum_with_torque("kick", "sqrt(0.503-t)", 0.01);
    let held = model.run("dynamics", &Default::default()).unwrap_err();
    let reference = temp("failed-held.csv");
    held.results.write_csv(&reference).unwrap();
    let path = temp("failed-streamed.csv");
    let sink = Box::new(CsvSink::at(&path));
    let streamed = model.run("dynamics", &streaming(sink)).unwrap_err();
    assert_eq!(streamed.error.to_string(), held.error.to_string());
    assert_eq!(streamed.results.len(), 51);
    assert_eq!(std::fs::read_to_string(&path).unwrap(), std::fs::read_to_string(&reference).unwrap());
    for p in [path, reference] {
        std::fs::remove_file(p).unwrap();
    }
}

/// A run that cannot start (an analysis that does not exist) leaves the file it would have
/// streamed to as it was.
#[test]
fn a_run_that_cannot_start_leaves_the_file_alone() {
    let path = temp("keep.csv");
    std::fs::write(&path, "kept\n").unwrap();
    let model = Model::load(example("quick_return_a.yaml")).unwrap();
    let sink = Box::new(CsvSink::at(&path));
    let failure = model.run("kinematcs", &streaming(sink)).unwrap_err();
    assert!(failure.error.to_string().contains("kinematcs"), "{}", failure.error);
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "kept\n");
    std::fs::remove_file(path).unwrap();
}

/// A sink whose writes fail (a full disk) fails the run with `Error::Io` naming its file.
#[test]
fn a_sink_that_cannot_be_written_fails_the_run_naming_it() {
    struct Full;
    impl RowSink for Full {
        fn begin(&mut self, _: &[String]) -> std::io::Result<()> {
            Ok(())
        }
        fn write(&mut self, _: &[f64], _: &[Vec<f64>]) -> std::io::Result<()> {
            Err(std::io::Error::other("no space left on device"))
        }
        fn finish(&mut self) -> std::io::Result<()> {
            Ok(())
        }
        fn path(&self) -> String {
            "/full/results.csv".into()
        }
        fn chunk_bytes(&self) -> usize {
            1
        }
    }
    let model = Model::load(example("quick_return_a.yaml")).unwrap();
    let failure = model.run("kinematics", &streaming(Box::new(Full))).unwrap_err();
    assert!(
        matches!(&failure.error, Error::Io { path, message } if path == "/full/results.csv" && message.contains("no space")),
        "{}",
        failure.error
    );
}

/// A CSV stream makes its file anew when it writes the header (under a temporary name, then
/// renamed over the old one): the previous file at its path is never truncated in place (it was,
/// on the first chunk), so a reader holding it, here a second name of it, still reads it whole.
#[test]
fn a_csv_stream_replaces_its_file_and_never_truncates_it() {
    let path = temp("replaced.csv");
    let old = temp("replaced-old.csv");
    std::fs::write(&path, "time,a.x\n0.0,1.0\n").unwrap();
    let _ = std::fs::remove_file(&old);
    std::fs::hard_link(&path, &old).unwrap();
    let mut sink = CsvSink::at(&path);
    sink.begin(&["b.y".to_string()]).unwrap();
    assert_eq!(std::fs::read_to_string(&old).unwrap(), "time,a.x\n0.0,1.0\n");
    sink.write(&[0.0, 0.5], &[vec![2.0, 3.0]]).unwrap();
    sink.finish().unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "time,b.y\n0.0,2.0\n0.5,3.0\n");
    assert_eq!(std::fs::read_to_string(&old).unwrap(), "time,a.x\n0.0,1.0\n");
    std::fs::remove_file(&path).unwrap();
    std::fs::remove_file(&old).unwrap();
}
