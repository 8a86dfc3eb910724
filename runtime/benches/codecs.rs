//! Wire-codec timings: decode a typical navdata packet (demo + checksum, target ≤ 1 µs),
//! decode a NatNet 4.1 frame with 3 rigid bodies (target ≤ 1 µs), encode the per-tick
//! AT datagram (PCMD + COMWDG), and map a generic command to PCMD values.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use dronecine_ardrone::at::{AtCommand, AtEncoder, Datagram, PcmdLimits};
use dronecine_ardrone::navdata::{self, ControlState, Demo, DroneState, Navdata, NavdataWriter};
use dronecine_backend::frames::Command;
use dronecine_natnet::frame::{
    decode_frame, encode_frame, Frame, FrameOut, MarkerSet, RigidBody, UpAxis, Version,
};
use dronecine_profile::Profile;

fn navdata_packet() -> Vec<u8> {
    let mut buf = [0u8; 4096];
    let mut w = NavdataWriter::new(&mut buf, DroneState(0x0080_0415), 1234, 1).unwrap();
    w.demo(&Demo {
        ctrl_state: ControlState::from_raw(3 << 16),
        battery_percent: 76,
        theta_mdeg: -1200.0,
        phi_mdeg: 800.0,
        psi_mdeg: 45_000.0,
        altitude_mm: 1500,
        vx_mmps: 120.0,
        vy_mmps: -40.0,
        vz_mmps: 5.0,
        num_frames: 0,
    })
    .unwrap();
    let n = w.finish().unwrap();
    buf[..n].to_vec()
}

fn natnet_frame() -> Vec<u8> {
    let markers = [[0.1f32, 1.0, 0.2], [0.0, 1.1, 0.1], [-0.1, 1.0, 0.0]];
    let sets = [
        MarkerSet {
            name: "drone",
            markers: &markers,
        },
        MarkerSet {
            name: "actor1",
            markers: &markers,
        },
        MarkerSet {
            name: "actor2",
            markers: &markers,
        },
    ];
    let bodies: Vec<RigidBody> = (1..=3)
        .map(|id| RigidBody {
            id,
            position_m: [id as f32, 1.2, -0.5],
            orientation_xyzw: [0.0, 0.3826834, 0.0, 0.9238795],
            mean_error_m: 0.0004,
            params: 1,
        })
        .collect();
    let out = FrameOut {
        frame_number: 100_000,
        marker_sets: &sets,
        rigid_bodies: &bodies,
        timestamp_s: 833.3,
        camera_mid_exposure_ticks: 1,
        camera_data_received_ticks: 2,
        transmit_ticks: 3,
        ..FrameOut::default()
    };
    let mut buf = vec![0u8; 4096];
    let n = encode_frame(&out, Version::V4_1, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn benches(c: &mut Criterion) {
    let packet = navdata_packet();
    let mut nav = Navdata::default();
    c.bench_function("navdata_decode_demo", |b| {
        b.iter(|| {
            navdata::decode(black_box(&packet), &mut nav).unwrap();
            black_box(&nav);
        })
    });

    let frame = natnet_frame();
    let mut f = Frame::default();
    c.bench_function("natnet_decode_4_1_three_bodies", |b| {
        b.iter(|| {
            decode_frame(black_box(&frame), Version::V4_1, &mut f).unwrap();
            black_box(&f);
        })
    });
    c.bench_function("natnet_decode_and_convert_3_bodies", |b| {
        b.iter(|| {
            decode_frame(black_box(&frame), Version::V4_1, &mut f).unwrap();
            for body in &f.rigid_bodies {
                black_box(body.body_pose(UpAxis::Y));
            }
        })
    });

    let limits = PcmdLimits::from_profile(&Profile::builtin("ardrone2").unwrap().limits).unwrap();
    let mut enc = AtEncoder::new();
    let mut buf = [0u8; 1024];
    let mut k = 0u32;
    c.bench_function("at_encode_pcmd_comwdg", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let t = f64::from(k % 1000) * 1e-3;
            let cmd = Command {
                roll_rad: 0.1 * t,
                pitch_rad: -0.05 * t,
                yaw_rate_radps: 0.3,
                vz_mps: -0.2 * t,
            };
            let mut dg = Datagram::new(&mut buf);
            enc.push(&mut dg, &AtCommand::Pcmd(limits.pcmd(black_box(&cmd))))
                .unwrap();
            enc.push(&mut dg, &AtCommand::Comwdg).unwrap();
            black_box(dg.len());
        })
    });
}

criterion_group!(codecs, benches);
criterion_main!(codecs);
