//! The binary run records of a part's body: a migration run (153 bytes), a scene run (186).

use super::*;

pub(super) fn encode_run(r: &RunSummary, out: &mut Vec<u8>) {
    // every field, so that a new one fails to compile here
    let RunSummary {
        time,
        speed,
        kinetic_energy,
        impact_count,
        runout,
        max_bounce_height,
        stop_reason,
        steps,
        along_dip_velocity,
        support,
        impact_speed,
        release_along_dip,
        release_across,
        side_length,
        density,
        stop_along_dip,
        stop_across,
        translational_energy,
        rotational_energy,
        passing_height,
    } = *r;
    for x in [
        time,
        speed,
        kinetic_energy,
        runout,
        max_bounce_height,
        along_dip_velocity,
        impact_speed,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&impact_count.to_le_bytes());
    out.extend_from_slice(&steps.to_le_bytes());
    out.extend_from_slice(&support.map_or(u64::MAX, |k| k as u64).to_le_bytes());
    out.push(match stop_reason {
        StopReason::LowerEnd => 0,
        StopReason::AtRest => 1,
        StopReason::EndTime => 2,
        StopReason::LeftFloor => 3,
        StopReason::Support => 4,
        StopReason::Barrier => 5,
    });
    // format version 4: the draws, the stop position and the energies and height at the end
    for x in [
        release_along_dip,
        release_across,
        side_length,
        density,
        stop_along_dip,
        stop_across,
        translational_energy,
        rotational_energy,
        passing_height,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

pub(super) fn decode_run(b: &[u8; RUN_RECORD_BYTES as usize]) -> Result<RunSummary, String> {
    let f = |k: usize| f64::from_le_bytes(std::array::from_fn(|i| b[8 * k + i]));
    let u = |k: usize| u64::from_le_bytes(std::array::from_fn(|i| b[8 * k + i]));
    // the fields of format version 4, after the stop-reason byte
    let g = |k: usize| f64::from_le_bytes(std::array::from_fn(|i| b[81 + 8 * k + i]));
    Ok(RunSummary {
        time: f(0),
        speed: f(1),
        kinetic_energy: f(2),
        runout: f(3),
        max_bounce_height: f(4),
        along_dip_velocity: f(5),
        impact_speed: f(6),
        impact_count: u(7),
        steps: u(8),
        support: match u(9) {
            u64::MAX => None,
            k => Some(usize::try_from(k).map_err(|_| format!("support index {k} out of range"))?),
        },
        stop_reason: match b[80] {
            0 => StopReason::LowerEnd,
            1 => StopReason::AtRest,
            2 => StopReason::EndTime,
            3 => StopReason::LeftFloor,
            4 => StopReason::Support,
            5 => StopReason::Barrier,
            x => return Err(format!("unknown stop reason code {x}")),
        },
        release_along_dip: g(0),
        release_across: g(1),
        side_length: g(2),
        density: g(3),
        stop_along_dip: g(4),
        stop_across: g(5),
        translational_energy: g(6),
        rotational_energy: g(7),
        passing_height: g(8),
    })
}

pub(super) fn encode_scene_run(r: &SceneRun, out: &mut Vec<u8>) {
    // every field, so that a new one fails to compile here
    let SceneRun {
        summary,
        values,
        capacity_exceeded,
        exceeded,
        guard,
        // a sharded scene has no lines (refused when asked): nothing to store
        crossings: _,
    } = r;
    encode_run(summary, out);
    let StrikeValues {
        max_deformation,
        max_force,
        absorbed_energy,
        stress_utilisation,
    } = values.unwrap_or_default();
    for x in [
        max_deformation,
        max_force,
        absorbed_energy,
        stress_utilisation,
    ] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    // bit 0: values present, bit 1: past the capacity, bits 2–4: exceeded per active limit (≤ 3),
    // bit 6: held by the guard, bit 7: broke through the guard
    debug_assert!(exceeded.len() <= 3);
    let mut flags = u8::from(values.is_some()) | (u8::from(*capacity_exceeded) << 1);
    for (j, &e) in exceeded.iter().enumerate() {
        flags |= u8::from(e) << (2 + j);
    }
    flags |= match guard {
        Guard::None => 0,
        Guard::Held => 1 << 6,
        Guard::BrokenThrough => 1 << 7,
    };
    out.push(flags);
}

pub(super) fn decode_scene_run(
    b: &[u8; SCENE_RECORD_BYTES as usize],
    limits: usize,
) -> Result<SceneRun, String> {
    let summary = decode_run(
        b[..RUN_RECORD_BYTES as usize]
            .try_into()
            .map_err(|_| "a scene record shorter than a run record".to_string())?,
    )?;
    let at = RUN_RECORD_BYTES as usize;
    let f = |k: usize| f64::from_le_bytes(std::array::from_fn(|i| b[at + 8 * k + i]));
    let flags = b[at + 32];
    let guard = match flags >> 6 {
        0 => Guard::None,
        1 => Guard::Held,
        2 => Guard::BrokenThrough,
        _ => {
            return Err(format!(
                "scene record flags {flags:#04x}: held and broken through"
            ));
        }
    };
    let flags = flags & 0x3f;
    if flags >> (2 + limits) != 0 {
        return Err(format!(
            "scene record flags {flags:#04x} do not fit {limits} limits"
        ));
    }
    Ok(SceneRun {
        summary,
        values: (flags & 1 != 0).then(|| StrikeValues {
            max_deformation: f(0),
            max_force: f(1),
            absorbed_energy: f(2),
            stress_utilisation: f(3),
        }),
        capacity_exceeded: flags & 2 != 0,
        exceeded: (0..limits).map(|j| flags & (4 << j) != 0).collect(),
        guard,
        crossings: Vec::new(),
    })
}
