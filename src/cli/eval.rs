//! `brdf-shop eval`: `f(ω_i, ω_o)` for lines of six numbers on stdin. All input is read and checked
//! before anything is printed, so a bad line gives no partial output.

use std::io::{BufRead, Read, Write};
use std::path::Path;

use brdf_shop::brdf::Material;
use brdf_shop::Error;
use glam::DVec3;

/// The longest input line (bytes, line break excluded): six numbers in their longest shortest form
/// are under 150 bytes, so 4 KiB leaves room for any spacing while a stray binary blob is refused at
/// once.
pub const MAX_LINE_BYTES: usize = 4096;

/// The most input read (bytes). All input is checked before anything is printed, so it is held: 64
/// MiB is at least a million lines, and with the parsed pairs (48 bytes each) and the output
/// (about 60 bytes a line) stays under a gigabyte.
pub const MAX_INPUT_BYTES: usize = 64 << 20;

fn parse_line(line: &str, no: usize) -> Result<(DVec3, DVec3), Error> {
    let origin = "stdin";
    let nums: Vec<&str> = line.split_whitespace().collect();
    if nums.len() != 6 {
        return Err(Error::input(
            origin,
            format!("line {no}: expected 6 numbers (wix wiy wiz wox woy woz), got {}", nums.len()),
        ));
    }
    let mut v = [0.0; 6];
    for (i, s) in nums.iter().enumerate() {
        v[i] = s.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
            Error::input(
                origin,
                format!("line {no}: field {}: \"{}\" is not a finite number", i + 1, brdf_shop::fsio::quote(s)),
            )
        })?;
    }
    let wi = DVec3::new(v[0], v[1], v[2]);
    let wo = DVec3::new(v[3], v[4], v[5]);
    for (name, d) in [("ω_i", wi), ("ω_o", wo)] {
        if d == DVec3::ZERO {
            return Err(Error::input(origin, format!("line {no}: {name} is the zero vector")));
        }
    }
    Ok((wi, wo))
}

pub fn run(material: &Path) -> anyhow::Result<()> {
    let m = Material::load(material)?;
    let stdin = std::io::stdin().lock();
    let mut input = stdin.take(MAX_INPUT_BYTES as u64 + 1);
    let mut pairs = Vec::new();
    let mut buf = Vec::new();
    let (mut no, mut total) = (0usize, 0usize);
    loop {
        buf.clear();
        no += 1;
        // At most one byte past the line limit is read, so a huge line is refused without holding it.
        let n = (&mut input)
            .take(MAX_LINE_BYTES as u64 + 2)
            .read_until(b'\n', &mut buf)
            .map_err(|e| Error::input("stdin", format!("cannot read: {e}")))?;
        if n == 0 {
            break;
        }
        total += n;
        if total > MAX_INPUT_BYTES {
            return Err(
                Error::input("stdin", format!("more than the limit of {MAX_INPUT_BYTES} bytes of input")).into()
            );
        }
        let line = buf.strip_suffix(b"\n").unwrap_or(&buf);
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.len() > MAX_LINE_BYTES {
            return Err(
                Error::input("stdin", format!("line {no}: longer than the limit of {MAX_LINE_BYTES} bytes")).into()
            );
        }
        let line =
            std::str::from_utf8(line).map_err(|_| Error::input("stdin", format!("line {no}: not UTF-8 text")))?;
        if line.trim().is_empty() {
            continue;
        }
        pairs.push(parse_line(line, no)?);
    }
    if pairs.is_empty() {
        return Err(Error::input("stdin", "no input: expected lines of 6 numbers (wix wiy wiz wox woy woz)").into());
    }
    let mut out = String::new();
    for (wi, wo) in pairs {
        let f = m.eval(wi, wo);
        out.push_str(&format!(
            "{} {} {}\n",
            brdf_shop::fsio::shortest(f[0]),
            brdf_shop::fsio::shortest(f[1]),
            brdf_shop::fsio::shortest(f[2])
        ));
    }
    std::io::stdout().write_all(out.as_bytes())?;
    Ok(())
}
