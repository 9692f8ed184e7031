//! `pvt3 import`: a folder of CSV touches → an `.npz` data set for `train`, `cv` and `eval`.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use pvt3_trainer::data::import::{read_folder, ImportOptions, NamePattern};

/// Read a folder of CSV recordings (one folder per class, one CSV file per touch, a header row,
/// touches of any length) into a data set.
///
/// Example: `pvt3 import csvs/ --out data.npz`, then `pvt3 cv --data data.npz`. Where the file
/// names say the class and how each touch was made: `pvt3 import fabric/ --name
/// '{class}_F{force}_V{speed}mmps_*'`, then `pvt3 cv --hold-out force=210,250` tests on forces
/// the training never saw.
#[derive(clap::Args)]
pub struct ImportArgs {
    /// The folder: DIR/<class>/<touch>.csv, class names the folder names; or, with --name
    /// naming the class, DIR/<touch>.csv.
    pub dir: PathBuf,
    /// The data set to write (`x`, `y`, `lengths`, class names, channels, the files read).
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
    /// What each file's name (without .csv) says: `{field}` reads a value, `*` matches anything,
    /// other characters match themselves. `{class}` names the class (the files then lie side by
    /// side in DIR); every other field is a condition of the touch (speed, force, …) recorded
    /// for `--hold-out`. E.g. `{class}_F{force}_V{speed}mmps_*`.
    #[arg(long, value_name = "PATTERN")]
    pub name: Option<NamePattern>,
    /// Read every touch by distance travelled, not by time: CONDITION=SPEED names the condition
    /// of --name that holds each touch's sliding speed, and the speed all touches are resampled
    /// to (a touch of n frames at speed v becomes n·|v|/SPEED frames). A texture's ridges then lie
    /// as many frames apart at every speed. E.g. `--per-distance speed=150`.
    #[arg(long, value_name = "CONDITION=SPEED", value_parser = parse_condition_value)]
    pub per_distance: Option<(String, f64)>,
    /// Scale every touch's readings to one pressing force: CONDITION=FORCE names the condition
    /// of --name that holds each touch's force, and the force all touches are scaled to
    /// (readings times FORCE/f for a touch pressed at f). E.g. `--per-force force=150`.
    #[arg(long, value_name = "CONDITION=FORCE", value_parser = parse_condition_value)]
    pub per_force: Option<(String, f64)>,
}

/// `CONDITION=VALUE`, the value a number above 0.
fn parse_condition_value(s: &str) -> std::result::Result<(String, f64), String> {
    let bad = || format!("`{s}`: expected CONDITION=VALUE with a value above 0, e.g. speed=150");
    let (name, value) = s.split_once('=').ok_or_else(bad)?;
    let value = value.trim().parse::<f64>().ok().filter(|v| v.is_finite() && *v > 0.0).ok_or_else(bad)?;
    Ok((name.trim().to_string(), value))
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
    let opts = ImportOptions { columns: a.columns, grid: a.grid, name: a.name, per_distance: a.per_distance, per_force: a.per_force };
    let set = read_folder(&a.dir, &opts)?;
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
    if let Some((name, speed)) = &opts.per_distance {
        println!("every touch resampled from time to distance: to the frames it would have at {name} {speed}");
    }
    if let Some((name, force)) = &opts.per_force {
        println!("every touch's readings scaled to {name} {force}");
    }
    for c in &set.conditions {
        println!("condition {}: {}", c.name, c.distinct().join(", "));
    }
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
