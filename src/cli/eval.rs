//! `brdf-shop eval`: `f(ω_i, ω_o)` for lines of six numbers on stdin. All input is read and checked
//! before anything is printed, so a bad line gives no partial output.

use std::io::{Read, Write};
use std::path::Path;

use brdf_shop::brdf::Material;
use brdf_shop::Error;
use glam::DVec3;

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
            Error::input(origin, format!("line {no}: field {}: \"{s}\" is not a finite number", i + 1))
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
    let mut text = String::new();
    std::io::stdin().read_to_string(&mut text).map_err(|e| Error::input("stdin", format!("cannot read: {e}")))?;
    let mut pairs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        pairs.push(parse_line(line, i + 1)?);
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
