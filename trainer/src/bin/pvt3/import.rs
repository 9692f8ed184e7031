//! `pvt3 import`: a folder of CSV touches → an `.npz` data set for `train`, `cv` and `eval`.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use pvt3_trainer::import::{read_folder, ImportOptions};

/// Read a folder of CSV recordings (one folder per class, one CSV file per touch, a header row,
/// touches of any length) into a data set.
///
/// Example: `pvt3 import csvs/ --out data.npz`, then `pvt3 cv --data data.npz`.
#[derive(clap::Args)]
pub struct ImportArgs {
    /// The folder: DIR/<class>/<touch>.csv. Class names are the folder names.
    pub dir: PathBuf,
    #[arg(short, long, default_value = "data.npz")]
    pub out: PathBuf,
    /// The sensor channels: column names or patterns (`*` any characters, `?` one), comma
    /// separated, e.g. `ff_e*` or `e1,e2,e3`. Default: every numeric column that varies,
    /// time stamps (by name, or rising in every touch) and constant columns left out.
    #[arg(long, value_delimiter = ',')]
    pub columns: Vec<String>,
    /// The chosen channels as a ROWSxCOLS grid, row-major (e.g. `6x10` for the iCub skin).
    /// Default: one column of channels, as for the BioTac's electrodes.
    #[arg(long, value_parser = parse_grid)]
    pub grid: Option<(usize, usize)>,
}

fn parse_grid(s: &str) -> std::result::Result<(usize, usize), String> {
    let parse = |v: &str| v.trim().parse::<usize>().ok().filter(|v| *v > 0);
    match s.split_once(['x', 'X', '×']) {
        Some((h, w)) => parse(h).zip(parse(w)).ok_or_else(|| format!("`{s}`: expected ROWSxCOLS, e.g. 6x10")),
        None => Err(format!("`{s}`: expected ROWSxCOLS, e.g. 6x10")),
    }
}

pub fn run(a: ImportArgs) -> Result<()> {
    if !a.dir.is_dir() {
        bail!("{} is not a folder (expected one folder per class of CSV files)", a.dir.display());
    }
    let set = read_folder(&a.dir, &ImportOptions { columns: a.columns, grid: a.grid })?;
    set.write_npz(&a.out).with_context(|| format!("writing {}", a.out.display()))?;
    let (shortest, longest) = set.length_range();
    let per_class = set.per_class();
    println!(
        "{} touches of {} classes ({} to {} touches a class), {shortest} to {longest} frames a touch",
        set.labels.len(),
        set.classes.len(),
        per_class.iter().min().unwrap_or(&0),
        per_class.iter().max().unwrap_or(&0)
    );
    let layout = match set.grid {
        Some((h, w)) => format!("a {h} × {w} grid"),
        None => "one column".into(),
    };
    println!("{} channels as {layout}: {}", set.channels.len(), set.channels.join(", "));
    for (name, why) in &set.left_out {
        println!("left out: {name} ({why})");
    }
    println!("wrote {}; next: pvt3 cv --data {}", a.out.display(), a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn grids_parse_rows_by_columns() {
        assert_eq!(super::parse_grid("6x10"), Ok((6, 10)));
        assert_eq!(super::parse_grid("19×1"), Ok((19, 1)));
        assert!(super::parse_grid("60").unwrap_err().contains("expected ROWSxCOLS"));
        assert!(super::parse_grid("0x4").is_err());
    }
}
