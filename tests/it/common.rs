//! Helpers shared by the CLI tests: run the binary, read its streams.

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `wfem` binary with `args` to completion.
pub fn wfem(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_wfem"))
        .args(args)
        .output()
        .expect("the wfem binary runs")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A CSV field file: its header and rows of numbers.
pub fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().ok_or("empty CSV")?.split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|x| x.parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
                .collect::<Result<Vec<f64>, String>>()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((header, rows))
}

/// An NPY 1.0 float64 file: its shape and data.
pub fn read_npy(path: &Path) -> Result<(Vec<usize>, Vec<f64>), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if !bytes.starts_with(b"\x93NUMPY\x01\x00") {
        return Err("not NPY 1.0".into());
    }
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + len]).map_err(|e| e.to_string())?;
    if !header.contains("'descr': '<f8'") {
        return Err(format!("dtype: {header}"));
    }
    let shape_text = header
        .split("'shape': (")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .ok_or("no shape")?;
    let shape: Vec<usize> = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().map_err(|_| format!("shape {shape_text}")))
        .collect::<Result<_, String>>()?;
    let data: Vec<f64> = bytes[10 + len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    Ok((shape, data))
}
