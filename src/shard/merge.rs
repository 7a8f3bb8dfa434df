//! `gangue merge`: the checked parts into the answer's bytes.

use super::part::{
    PartRuns, SceneRuns, check_parts, check_sections, part_zero, read_part, read_section, read_u64,
    reader,
};
use super::*;
use crate::physics::migration::maps::{MapGrid, Maps, build_maps};

/// `gangue merge`: checks the parts and writes the response body to `out`; `wire` reads the
/// request and writes the answer.
pub fn merge<W: Wire>(args: &MergeArgs, wire: &W, out: &mut dyn Write) -> Result<(), Failure> {
    args.limits.validate()?;
    let mut parts = args
        .parts
        .iter()
        .map(|p| read_part(p))
        .collect::<Result<Vec<_>, _>>()?;
    check_parts(&mut parts)?;
    let h = parts[0].header.clone();
    let kind = Kind::from_name(&h.kind).ok_or_else(|| format!("unknown kind {:?}", h.kind))?;
    if h.build != build_id() {
        return Err(Failure::from(format!(
            "the parts were computed by {}, this merge is {}: merge with the same gangue binary",
            h.build,
            build_id()
        )));
    }
    let config = &args.limits;
    let r = resolve(wire, kind, h.request.as_bytes(), config)?;
    if r.hash != h.inputs_sha256 {
        return Err(Failure::from(
            "the request resolves to other inputs under this merge's limits than under the \
             parts': give the merge the same limit flags as the computation"
                .to_string(),
        ));
    }
    let ctl = control(args.time_limit_s);
    let bytes = match r.prepared {
        Prepared::Migration { case, req } => {
            let mut report =
                calc::migration::merge(&case, &PartRuns(&parts), &ctl).map_err(|e| match e {
                    MergeError::Physics(e) => wire.physics_failure(e),
                    MergeError::Records(e) => Failure::from(e),
                })?;
            if let Some(grid) = &case.output.maps {
                report.result.maps = Some(merged_maps(&parts, grid)?);
            }
            wire.migration_answer(report, *req)?
        }
        Prepared::Scene { case, req, .. } => {
            let ensemble = calc::scene::ensemble(&case);
            let per = 1 + case.supports.len() * (ENTRY_COLUMNS + REACH_COLUMNS);
            let streams = match ensemble {
                Some(_) => 1 + usize::from(case.compare_methods),
                None => 0,
            };
            check_sections(
                &parts,
                streams * per + 1,
                ensemble.map(|_| SCENE_RECORD_BYTES),
            )?;
            let p0 = part_zero(&parts, "the nominal run and its impacts")?;
            let head: W::SceneHead = serde_json::from_slice(&read_section(p0, streams * per)?)
                .map_err(|e| {
                    format!(
                        "{}: the stored nominal part is damaged: {e}",
                        p0.path.display()
                    )
                })?;
            let limits = case.limits.active().len();
            let main = SceneRuns {
                parts: &parts,
                first: 0,
                limits,
                entries: case.supports.len(),
            };
            let other = case.compare_methods.then_some(SceneRuns {
                parts: &parts,
                first: per,
                limits,
                entries: case.supports.len(),
            });
            let tail = calc::scene::merge(
                &case,
                W::nominal_capacity(&head),
                &main,
                other.as_ref(),
                W::keep_runs(&req),
            )?;
            wire.scene_answer(head, tail, &case, *req)?
        }
        Prepared::Study(plan) => {
            check_sections(&parts, 2, None)?;
            let mut results = Vec::with_capacity(W::study_points(&plan) as usize);
            let p0 = part_zero(&parts, "the study's base point")?;
            let base = read_section(p0, 1)?;
            let (len, values) = base.split_first_chunk::<8>().ok_or_else(|| {
                format!("{}: the stored base point is damaged", p0.path.display())
            })?;
            let len = u64::from_le_bytes(*len);
            if values.len() as u64 != len * 8 {
                return Err(Failure::from(format!(
                    "{}: the stored base point is damaged",
                    p0.path.display()
                )));
            }
            results.push(
                values
                    .chunks_exact(8)
                    .map(|b| f64::from_le_bytes(std::array::from_fn(|i| b[i])))
                    .collect(),
            );
            for p in &parts {
                let mut r = reader(p, 0)?;
                for _ in p.header.start..p.header.end {
                    let len = read_u64(&mut r, p)?;
                    let mut v = Vec::with_capacity(len.min(1 << 16) as usize);
                    for _ in 0..len {
                        v.push(f64::from_bits(read_u64(&mut r, p)?));
                    }
                    results.push(v);
                }
            }
            wire.study_answer(*plan, results)?
        }
        Prepared::Batch(_) => {
            // the answer lines, streamed in index order
            for p in &parts {
                let mut r = reader(p, 0)?;
                for _ in p.header.start..p.header.end {
                    let len = read_u64(&mut r, p)?;
                    let mut l = vec![0u8; len as usize];
                    r.read_exact(&mut l)
                        .map_err(|e| format!("{}: {e}", p.path.display()))?;
                    out.write_all(&l)
                        .map_err(|e| format!("writing the answer: {e}"))?;
                }
            }
            Vec::new()
        }
    };
    out.write_all(&bytes)
        .and_then(|()| out.flush())
        .map_err(|e| Failure::from(format!("writing the answer: {e}")))
}

/// The maps of a migration from its parts' maps sections (after the records and the seven
/// columns), the runs in index order: the maps of the same request computed at once.
fn merged_maps(parts: &[super::part::Part], grid: &MapGrid) -> Result<Maps, String> {
    check_sections(parts, 1 + STATISTICS_COLUMNS + 1, Some(RUN_RECORD_BYTES))?;
    let mut cells = Vec::new();
    for p in parts {
        let b = read_section(p, 1 + STATISTICS_COLUMNS)?;
        cells.extend(
            super::compute::decode_cells(&b, p.header.end - p.header.start)
                .map_err(|e| format!("{}: {e}", p.path.display()))?,
        );
    }
    Ok(build_maps(grid, &cells))
}
