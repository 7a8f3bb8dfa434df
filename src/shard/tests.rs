//! Tests of the shard ranges, the shard index and the run records.

use super::*;

#[test]
fn shard_ranges_tile_the_items() {
    for n in [0u64, 1, 2, 7, 100, 1_000_003] {
        for k in [1u64, 2, 3, 7, 64] {
            let mut next = 0;
            for i in 0..k {
                let r = shard_range(i, k, n);
                assert_eq!(r.start, next);
                next = r.end;
            }
            assert_eq!(next, n);
        }
    }
    assert_eq!(shard_range(1, 3, 10), 3..6);
}

#[test]
fn run_records_round_trip() {
    let r = RunSummary {
        time: 1.5,
        speed: -0.0,
        kinetic_energy: 3e300,
        impact_count: 7,
        runout: 5e-324,
        max_bounce_height: 0.25,
        stop_reason: StopReason::LeftFloor,
        steps: u64::MAX,
        along_dip_velocity: -2.5,
        support: Some(3),
        impact_speed: 1.25,
        release_along_dip: 17.5,
        release_across: -1.0e-310,
        side_length: 0.3,
        density: 2650.0,
        stop_along_dip: 120.0,
        stop_across: -0.0,
        translational_energy: 9.5,
        rotational_energy: 0.0,
        passing_height: 2.5e-3,
    };
    let mut b = Vec::new();
    encode_run(&r, &mut b);
    assert_eq!(b.len() as u64, RUN_RECORD_BYTES);
    let back = decode_run(b.as_slice().try_into().unwrap()).unwrap();
    assert_eq!(back.speed.to_bits(), r.speed.to_bits());
    // the fields of format version 4, bit for bit (−0 and a subnormal included)
    assert_eq!(back.stop_across.to_bits(), r.stop_across.to_bits());
    assert_eq!(back.release_across.to_bits(), r.release_across.to_bits());
    assert_eq!(back, r);
}

#[test]
fn scene_run_records_round_trip() {
    let summary = RunSummary {
        time: 0.0,
        speed: 4.5,
        kinetic_energy: 12.0,
        impact_count: 2,
        runout: 7.25,
        max_bounce_height: 0.125,
        stop_reason: StopReason::Support,
        steps: 99,
        along_dip_velocity: 4.0,
        support: Some(2),
        impact_speed: 3.75,
        release_along_dip: 40.0,
        release_across: 0.75,
        side_length: 0.25,
        density: 2100.0,
        stop_along_dip: 47.25,
        stop_across: 0.5,
        translational_energy: 11.0,
        rotational_energy: 1.0,
        passing_height: 0.0,
    };
    let runs = [
        SceneRun {
            summary,
            values: Some(StrikeValues {
                max_deformation: 1e-3,
                max_force: -0.0,
                absorbed_energy: 5e-324,
                stress_utilisation: 1.5,
            }),
            capacity_exceeded: false,
            exceeded: vec![true, false, true],
            guard: Guard::BrokenThrough,
            crossings: Vec::new(),
        },
        SceneRun {
            summary,
            values: None,
            capacity_exceeded: true,
            exceeded: vec![true, true, true],
            guard: Guard::None,
            crossings: Vec::new(),
        },
        SceneRun {
            summary: RunSummary {
                support: None,
                stop_reason: StopReason::AtRest,
                ..summary
            },
            values: None,
            capacity_exceeded: false,
            exceeded: vec![false, false, false],
            guard: Guard::Held,
            crossings: Vec::new(),
        },
    ];
    for r in &runs {
        let mut b = Vec::new();
        encode_scene_run(r, &mut b);
        assert_eq!(b.len() as u64, SCENE_RECORD_BYTES);
        let back = decode_scene_run(b.as_slice().try_into().unwrap(), 3).unwrap();
        assert_eq!(&back, r);
        if let (Some(a), Some(b)) = (back.values, r.values) {
            assert_eq!(a.max_force.to_bits(), b.max_force.to_bits());
        }
        // a record of more limits than the request has is refused
        assert!(
            decode_scene_run(b.as_slice().try_into().unwrap(), 1).is_err()
                || r.exceeded[1..].iter().all(|e| !e)
        );
    }
}

fn args(shard: Option<&str>, shards: Option<u64>, offset: u64) -> ComputeArgs {
    ComputeArgs {
        request: "case.json".into(),
        kind: Kind::Migration,
        shard: shard.map(Into::into),
        shards,
        index_offset: offset,
        out: "part-{shard}".into(),
        time_limit_s: None,
        limits: Config::default(),
    }
}

#[test]
fn shard_index_from_flags_and_schedulers() {
    let none = |_: &str| None;
    assert_eq!(shard_of(&args(Some("2/5"), None, 0), &none), Ok((2, 5)));
    assert_eq!(shard_of(&args(None, None, 0), &none), Ok((0, 1)));
    let k8s = |n: &str| (n == "JOB_COMPLETION_INDEX").then(|| "3".to_string());
    assert_eq!(shard_of(&args(None, Some(8), 0), &k8s), Ok((3, 8)));
    assert!(
        shard_of(&args(None, None, 0), &k8s)
            .unwrap_err()
            .contains("--shards")
    );
    let slurm = |n: &str| match n {
        "SLURM_ARRAY_TASK_ID" => Some("1".to_string()),
        "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
        _ => None,
    };
    assert_eq!(shard_of(&args(None, None, 0), &slurm), Ok((1, 4)));
    // a second array of a split: offset 4, 7 shards in all
    assert_eq!(shard_of(&args(None, Some(7), 4), &slurm), Ok((5, 7)));
    let aws = |n: &str| (n == "AWS_BATCH_JOB_ARRAY_INDEX").then(|| "0".to_string());
    assert_eq!(shard_of(&args(None, Some(2), 0), &aws), Ok((0, 2)));
    for bad in ["3", "1/0", "a/3", "3/3"] {
        assert!(shard_of(&args(Some(bad), None, 0), &none).is_err(), "{bad}");
    }
}
