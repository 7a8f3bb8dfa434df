//! `gangue compute`: the items of one shard into a part file.

use super::*;
use crate::physics::migration::maps::{CellMax, RunCells};

/// `gangue compute`: computes the items of one shard and writes its part file. Returns the path
/// written. `wire` reads the request and writes the answer pieces part 0 stores.
pub fn compute<W: Wire>(args: &ComputeArgs, wire: &W) -> Result<PathBuf, Failure> {
    args.limits.validate()?;
    let (i, k) = shard_of(args, &|n| std::env::var(n).ok())?;
    let request = std::fs::read(&args.request).map_err(|e| io_err(&args.request, e))?;
    let request_text = String::from_utf8(request.clone())
        .map_err(|_| format!("{}: the request is not UTF-8", args.request.display()))?;
    let config = &args.limits;
    let r = resolve(wire, args.kind, &request, config)?;
    let range = shard_range(i, k, r.items);
    let mut sections = Vec::new();
    let mut body: Vec<u8> = Vec::new();
    match &r.prepared {
        Prepared::Migration { case, .. } => {
            let ctl = control(args.time_limit_s);
            let (runs, cells) = if case.output.maps.is_some() {
                let (runs, cells) = calc::migration::part_with_maps(case, range.clone(), &ctl)
                    .map_err(|e| wire.physics_failure(e))?;
                (runs, Some(cells))
            } else {
                let runs = Migration::part(case, range.clone(), &ctl)
                    .map_err(|e| wire.physics_failure(e))?;
                (runs, None)
            };
            for run in &runs {
                encode_run(run, &mut body);
            }
            sections.push(body.len() as u64);
            for col in 0..STATISTICS_COLUMNS {
                let mut v: Vec<f64> = runs.iter().filter_map(|r| run_columns(r)[col]).collect();
                v.sort_unstable_by(f64::total_cmp);
                let before = body.len();
                v.iter()
                    .for_each(|x| body.extend_from_slice(&x.to_le_bytes()));
                sections.push((body.len() - before) as u64);
            }
            // with maps, a section of its own after the columns: each run's cells
            if let Some(cells) = &cells {
                let before = body.len();
                cells.iter().for_each(|c| encode_cells(c, &mut body));
                sections.push((body.len() - before) as u64);
            }
        }
        Prepared::Scene { case, req } => {
            let ctl = control(args.time_limit_s);
            let fail = |e: SceneError| wire.scene_failure(e, req);
            // part 0: what is not an item, computed first (a refused request fails here)
            let ensemble = calc::scene::ensemble(case).is_some();
            let head = if i == 0 {
                let report = calc::scene::nominal(case, &ctl).map_err(fail)?;
                Some(wire.scene_head(&report, ensemble, case, req)?)
            } else {
                None
            };
            if ensemble {
                let (runs, other) = Scene::part(case, range.clone(), &ctl).map_err(fail)?;
                for stream in std::iter::once(&runs).chain(other.as_ref()) {
                    let before = body.len();
                    stream.iter().for_each(|r| encode_scene_run(r, &mut body));
                    sections.push((body.len() - before) as u64);
                    let mut columns = vec![vec![Vec::new(); ENTRY_COLUMNS]; case.supports.len()];
                    for (k, x) in stream.iter().filter_map(entry_columns) {
                        for (c, x) in columns[k].iter_mut().zip(x) {
                            c.push(x);
                        }
                    }
                    let mut reach = vec![vec![Vec::new(); REACH_COLUMNS]; case.supports.len()];
                    for (k, x) in stream.iter().filter_map(reach_columns) {
                        for (c, x) in reach[k].iter_mut().zip(x) {
                            c.push(x);
                        }
                    }
                    for mut v in columns.into_iter().chain(reach).flatten() {
                        v.sort_unstable_by(f64::total_cmp);
                        let before = body.len();
                        v.iter()
                            .for_each(|x| body.extend_from_slice(&x.to_le_bytes()));
                        sections.push((body.len() - before) as u64);
                    }
                }
            }
            let before = body.len();
            if let Some(h) = &head {
                serde_json::to_writer(&mut body, h).map_err(|e| format!("storing part 0: {e}"))?;
            }
            sections.push((body.len() - before) as u64);
        }
        Prepared::Study(plan) => {
            let ctl = control(args.time_limit_s);
            let out: Vec<Vec<f64>> = (range.start..range.end)
                .into_par_iter()
                .map(|g| wire.study_point(plan, config, g as usize + 1, &ctl))
                .collect::<Result<_, _>>()?;
            let values = |v: &[f64], body: &mut Vec<u8>| {
                body.extend_from_slice(&(v.len() as u64).to_le_bytes());
                v.iter()
                    .for_each(|x| body.extend_from_slice(&x.to_le_bytes()));
            };
            for v in &out {
                values(v, &mut body);
            }
            sections.push(body.len() as u64);
            // part 0: the base point, not an item
            let before = body.len();
            if i == 0 {
                values(&wire.study_point(plan, config, 0, &ctl)?, &mut body);
            }
            sections.push((body.len() - before) as u64);
        }
        Prepared::Batch(items) => {
            // each item has a time limit of its own (api.md), here none unless asked for
            let lines: Vec<bytes::Bytes> = (range.start..range.end)
                .into_par_iter()
                .map(|g| {
                    let g = g as usize;
                    let ctl = control(args.time_limit_s);
                    wire.batch_line(g, &items[g], config, &ctl)
                })
                .collect();
            for l in &lines {
                body.extend_from_slice(&(l.len() as u64).to_le_bytes());
                body.extend_from_slice(l);
            }
            sections.push(body.len() as u64);
        }
    }
    let header = Header {
        format: FORMAT.into(),
        version: FORMAT_VERSION,
        kind: args.kind.name().into(),
        build: build_id(),
        inputs_sha256: r.hash,
        request: request_text,
        items: r.items,
        shard: i,
        shards: k,
        start: range.start,
        end: range.end,
        sections,
    };
    let out = PathBuf::from(args.out.replace("{shard}", &i.to_string()));
    write_part(&out, &header, &body)?;
    Ok(out)
}

pub(super) fn write_part(out: &Path, header: &Header, body: &[u8]) -> Result<(), Failure> {
    let name = out
        .file_name()
        .ok_or_else(|| format!("--out {}: not a file name", out.display()))?;
    let tmp = out.with_file_name(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let write = || -> std::io::Result<()> {
        let mut w = BufWriter::new(File::create(&tmp)?);
        serde_json::to_writer(&mut w, header)?;
        w.write_all(b"\n")?;
        w.write_all(body)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, out)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_err(out, e)
    })
}

/// Bytes of one cell of a run in a part's maps section: index (u32), speed and kinetic energy
/// (f64), little-endian.
pub(super) const CELL_BYTES: usize = 20;

/// Appends one run's cells to a part's maps section: their count (u64), then each cell.
fn encode_cells(cells: &RunCells, body: &mut Vec<u8>) {
    body.extend_from_slice(&(cells.len() as u64).to_le_bytes());
    for c in cells {
        body.extend_from_slice(&c.cell.to_le_bytes());
        body.extend_from_slice(&c.speed.to_le_bytes());
        body.extend_from_slice(&c.kinetic_energy.to_le_bytes());
    }
}

/// The runs' cells of a part's maps section (see [`encode_cells`]), `runs` of them.
pub(super) fn decode_cells(b: &[u8], runs: u64) -> Result<Vec<RunCells>, String> {
    let mut out = Vec::with_capacity(usize::try_from(runs).unwrap_or(0));
    let mut at = 0usize;
    let take = |at: &mut usize, n: usize| -> Result<&[u8], String> {
        let s = b
            .get(*at..*at + n)
            .ok_or_else(|| "the maps section is short".to_string())?;
        *at += n;
        Ok(s)
    };
    for _ in 0..runs {
        let n = u64::from_le_bytes(take(&mut at, 8)?.try_into().map_err(|_| "count")?);
        let n = usize::try_from(n).map_err(|_| "a run's cell count does not fit")?;
        if n > (b.len() - at) / CELL_BYTES {
            return Err("the maps section is short".into());
        }
        let mut run = Vec::with_capacity(n);
        for _ in 0..n {
            let c = take(&mut at, CELL_BYTES)?;
            let f = |k: usize| f64::from_le_bytes(c[k..k + 8].try_into().unwrap_or([0; 8]));
            run.push(CellMax {
                cell: u32::from_le_bytes(c[0..4].try_into().unwrap_or([0; 4])),
                speed: f(4),
                kinetic_energy: f(12),
            });
        }
        out.push(run);
    }
    if at != b.len() {
        return Err("the maps section is longer than its runs".into());
    }
    Ok(out)
}
