//! NatNet codecs against the SDK layouts: hand-built 3.0 and 4.1 frames with every section
//! filled (skipped exactly by count or byte size), the handshake messages, encoder → decoder
//! round trips for 3.0/3.1/4.0/4.1, rejection of malformed frames, no panic on truncated or
//! random input, and the axis conversion.

use std::f64::consts::{FRAC_PI_2, PI};

use dronecine_natnet::frame::{
    decode_connect, decode_frame, decode_frame_payload, decode_server_info, encode_connect,
    encode_frame, encode_server_info, split_message, to_world, Frame, FrameOut, LabeledMarker,
    MarkerSet, NatNetError, RigidBody, ServerDetails, ServerInfo, UpAxis, Version, NAT_FRAMEOFDATA,
};
use proptest::prelude::*;

/// A little-endian byte builder for hand-written messages (independent of the encoder).
#[derive(Default, Clone)]
struct B(Vec<u8>);

impl B {
    fn put(mut self, b: &[u8]) -> Self {
        self.0.extend_from_slice(b);
        self
    }
    fn u16(self, v: u16) -> Self {
        self.put(&v.to_le_bytes())
    }
    fn i32(self, v: i32) -> Self {
        self.put(&v.to_le_bytes())
    }
    fn u32(self, v: u32) -> Self {
        self.put(&v.to_le_bytes())
    }
    fn u64(self, v: u64) -> Self {
        self.put(&v.to_le_bytes())
    }
    fn f32(self, v: f32) -> Self {
        self.put(&v.to_le_bytes())
    }
    fn f64(self, v: f64) -> Self {
        self.put(&v.to_le_bytes())
    }
    fn f32s(self, v: &[f32]) -> Self {
        v.iter().fold(self, |b, x| b.f32(*x))
    }
    /// A section: count, then (4.1) the byte count of `body`, then `body`.
    fn section(self, sized: bool, count: i32, body: B) -> Self {
        let b = self.i32(count);
        let b = if sized { b.i32(body.0.len() as i32) } else { b };
        b.put(&body.0)
    }
    /// Wraps a payload in the message header.
    fn message(self, id: u16) -> Vec<u8> {
        B::default().u16(id).u16(self.0.len() as u16).put(&self.0).0
    }
}

fn rigid_body(id: i32, p: [f32; 3], q: [f32; 4], err: f32, params: u16) -> B {
    B::default().i32(id).f32s(&p).f32s(&q).f32(err).u16(params)
}

/// A frame with every section populated, laid out for 3.x/4.0 (`sized` false) or 4.1.
fn hand_frame(sized: bool) -> Vec<u8> {
    let b = B::default().i32(12345); // frame number
                                     // Marker sets: "drone" with 2 markers, "all" with 1.
    let sets = B::default()
        .put(b"drone\0")
        .i32(2)
        .f32s(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
        .put(b"all\0")
        .i32(1)
        .f32s(&[7.0, 8.0, 9.0]);
    let b = b.section(sized, 2, sets);
    // Other markers: 1.
    let b = b.section(sized, 1, B::default().f32s(&[0.1, 0.2, 0.3]));
    // Rigid bodies: 2 (the second not tracked).
    let bodies = rigid_body(1, [0.5, 1.2, -0.25], [0.0, 0.0, 0.0, 1.0], 0.0005, 1).put(
        &rigid_body(
            7,
            [-1.0, 0.8, 2.0],
            [0.0, 0.70710677, 0.0, 0.70710677],
            0.001,
            0,
        )
        .0,
    );
    let b = b.section(sized, 2, bodies);
    // Skeletons: 1 with 2 bones.
    let skel = B::default()
        .i32(3)
        .i32(2)
        .put(&rigid_body(65537, [0.0; 3], [0.0, 0.0, 0.0, 1.0], 0.0, 1).0)
        .put(&rigid_body(65538, [0.0; 3], [0.0, 0.0, 0.0, 1.0], 0.0, 1).0);
    let b = b.section(sized, 1, skel);
    // Assets (4.1): 1 asset, 1 rigid body, 1 marker.
    let b = if sized {
        let asset = B::default()
            .i32(9)
            .i32(1)
            .put(&rigid_body(90, [1.0; 3], [0.0, 0.0, 0.0, 1.0], 0.0, 1).0)
            .i32(1)
            .i32(91)
            .f32s(&[1.0, 1.0, 1.0])
            .f32(0.014)
            .u16(0)
            .f32(0.0);
        assert_eq!(asset.0.len(), 4 + 4 + 38 + 4 + 26);
        b.section(true, 1, asset)
    } else {
        b
    };
    // Labeled markers: 2.
    let lm = B::default()
        .i32(0x0001_0002)
        .f32s(&[1.0, 2.0, 3.0])
        .f32(0.014)
        .u16(0x0A)
        .f32(0.0002)
        .i32(77)
        .f32s(&[4.0, 5.0, 6.0])
        .f32(0.01)
        .u16(0x10)
        .f32(0.0);
    let b = b.section(sized, 2, lm);
    // Force plates: 1 plate, 2 channels (3 frames, 0 frames).
    let fp = B::default()
        .i32(5)
        .i32(2)
        .i32(3)
        .f32s(&[1.0, 2.0, 3.0])
        .i32(0);
    let b = b.section(sized, 1, fp);
    // Devices: 1 device, 1 channel, 2 frames.
    let dev = B::default().i32(6).i32(1).i32(2).f32s(&[0.5, 0.25]);
    let b = b.section(sized, 1, dev);
    // Suffix.
    let b = b
        .u32(0x0102_0304)
        .u32(5)
        .f64(123.456)
        .u64(1_000_000)
        .u64(1_000_500)
        .u64(1_001_000);
    let b = if sized {
        b.u32(1_700_000_000).u32(42)
    } else {
        b
    };
    b.u16(0b10).i32(0).message(NAT_FRAMEOFDATA)
}

fn check_hand_frame(f: &Frame, sized: bool) {
    assert_eq!(f.frame_number, 12345);
    assert_eq!(f.marker_set_count, 2);
    assert_eq!(f.other_marker_count, 1);
    assert_eq!(
        f.rigid_bodies,
        [
            RigidBody {
                id: 1,
                position_m: [0.5, 1.2, -0.25],
                orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
                mean_error_m: 0.0005,
                params: 1
            },
            RigidBody {
                id: 7,
                position_m: [-1.0, 0.8, 2.0],
                orientation_xyzw: [0.0, 0.70710677, 0.0, 0.70710677],
                mean_error_m: 0.001,
                params: 0
            },
        ]
    );
    assert!(f.rigid_bodies[0].tracking_valid() && !f.rigid_bodies[1].tracking_valid());
    assert_eq!(f.skeleton_count, 1);
    assert_eq!(f.asset_count, u32::from(sized));
    assert_eq!(f.labeled_marker_count, 2);
    assert_eq!(f.force_plate_count, 1);
    assert_eq!(f.device_count, 1);
    assert_eq!((f.timecode, f.timecode_sub), (0x0102_0304, 5));
    assert_eq!(f.timestamp_s, 123.456);
    assert_eq!(
        (
            f.camera_mid_exposure_ticks,
            f.camera_data_received_ticks,
            f.transmit_ticks
        ),
        (1_000_000, 1_000_500, 1_001_000)
    );
    if sized {
        assert_eq!(
            (f.precision_timestamp_secs, f.precision_timestamp_frac_secs),
            (1_700_000_000, 42)
        );
    } else {
        assert_eq!(f.precision_timestamp_secs, 0);
    }
    assert!(f.tracked_models_changed() && !f.is_recording());
    assert_eq!(f.rigid_body(7).map(|b| b.id), Some(7));
    assert!(f.rigid_body(2).is_none());
}

#[test]
fn hand_built_3x_and_40_frames_decode() {
    let d = hand_frame(false);
    for v in [Version::V3_0, Version::V3_1, Version::V4_0] {
        let mut f = Frame::default();
        decode_frame(&d, v, &mut f).unwrap();
        check_hand_frame(&f, false);
    }
}

#[test]
fn hand_built_41_frame_decodes() {
    let d = hand_frame(true);
    let mut f = Frame::default();
    decode_frame(&d, Version::V4_1, &mut f).unwrap();
    check_hand_frame(&f, true);
}

#[test]
fn the_wrong_version_is_an_error_not_a_misparse() {
    let mut f = Frame::default();
    assert!(decode_frame(&hand_frame(true), Version::V4_0, &mut f).is_err());
    assert!(decode_frame(&hand_frame(false), Version::V4_1, &mut f).is_err());
    for v in [
        Version::new(2, 9, 0, 0),
        Version::new(4, 2, 0, 0),
        Version::new(5, 0, 0, 0),
    ] {
        assert_eq!(
            decode_frame(&hand_frame(false), v, &mut f),
            Err(NatNetError::UnsupportedVersion(v))
        );
    }
}

#[test]
fn decoding_reuses_the_rigid_body_vector() {
    let mut f = Frame::default();
    decode_frame(&hand_frame(true), Version::V4_1, &mut f).unwrap();
    let cap = f.rigid_bodies.capacity();
    let ptr = f.rigid_bodies.as_ptr();
    decode_frame(&hand_frame(true), Version::V4_1, &mut f).unwrap();
    assert_eq!(f.rigid_bodies.len(), 2);
    assert_eq!(
        (f.rigid_bodies.capacity(), f.rigid_bodies.as_ptr()),
        (cap, ptr)
    );
}

#[test]
fn every_truncation_is_an_error() {
    for sized in [false, true] {
        let v = if sized { Version::V4_1 } else { Version::V3_0 };
        let d = hand_frame(sized);
        let payload = &d[4..];
        let mut f = Frame::default();
        for k in 0..payload.len() {
            // The payload cut (header fixed up to match), and the datagram cut.
            assert!(
                decode_frame_payload(&payload[..k], v, &mut f).is_err(),
                "{v} {k}"
            );
            let cut = B::default().put(&payload[..k]).message(NAT_FRAMEOFDATA);
            assert!(decode_frame(&cut, v, &mut f).is_err());
            assert!(decode_frame(&d[..k + 4], v, &mut f).is_err());
        }
    }
}

#[test]
fn malformed_frames_are_rejected() {
    let mut f = Frame::default();
    let v = Version::V3_0;
    let d = hand_frame(false);
    // Trailing bytes inside the payload.
    let mut p = d[4..].to_vec();
    p.push(0);
    assert!(matches!(
        decode_frame_payload(&p, v, &mut f),
        Err(NatNetError::TrailingBytes { .. })
    ));
    // Datagram longer than the header says.
    let mut long = d.clone();
    long.push(0);
    assert!(matches!(
        decode_frame(&long, v, &mut f),
        Err(NatNetError::LengthMismatch { .. })
    ));
    // Not a frame.
    let mut other = d.clone();
    other[0] = 5;
    assert_eq!(
        decode_frame(&other, v, &mut f),
        Err(NatNetError::WrongMessage {
            expected: NAT_FRAMEOFDATA,
            got: 5
        })
    );
    // A negative count and a huge count (no huge allocation: refused up front).
    for count in [-1i32, i32::MAX] {
        let p = B::default().i32(1).i32(0).i32(0).i32(count).0;
        assert_eq!(
            decode_frame_payload(&p, v, &mut f),
            Err(NatNetError::BadCount { offset: 12 })
        );
    }
    // A marker-set name without its NUL.
    let p = B::default().i32(1).i32(1).put(b"drone").0;
    assert!(decode_frame_payload(&p, v, &mut f).is_err());
    // 4.1: a rigid-body byte count that disagrees with 38 × count, and one past the end.
    let p41 = |rb_size: i32| {
        B::default()
            .i32(1)
            .i32(0)
            .i32(0) // marker sets
            .i32(0)
            .i32(0) // other markers
            .i32(1)
            .i32(rb_size)
            .put(&rigid_body(1, [0.0; 3], [0.0, 0.0, 0.0, 1.0], 0.0, 1).0)
            .put(&[0u8; 200])
            .0
    };
    assert!(matches!(
        decode_frame_payload(&p41(40), Version::V4_1, &mut f),
        Err(NatNetError::BadSectionSize {
            section: "rigid body",
            ..
        })
    ));
    assert!(matches!(
        decode_frame_payload(&p41(100_000), Version::V4_1, &mut f),
        Err(NatNetError::BadCount { .. } | NatNetError::BadSectionSize { .. })
    ));
    // 4.1: a skipped section whose byte count runs past the end.
    let p = B::default().i32(1).i32(1).i32(1_000).put(&[0u8; 20]).0;
    assert!(matches!(
        decode_frame_payload(&p, Version::V4_1, &mut f),
        Err(NatNetError::BadSectionSize {
            section: "marker set",
            ..
        })
    ));
}

#[test]
fn connect_request_is_the_sdk_layout() {
    let mut buf = [0u8; 512];
    let n = encode_connect(Version::V4_1, &mut buf).unwrap();
    let d = &buf[..n];
    assert_eq!(n, 4 + 271);
    assert_eq!(&d[..4], &[0, 0, 0x0F, 0x01]); // id 0, 271 bytes
    assert_eq!(&d[4..8], b"Ping");
    assert!(d[8..4 + 265].iter().all(|&b| b == 0));
    assert_eq!(&d[4 + 265..4 + 269], &[4, 1, 0, 0]);
    assert_eq!(&d[4 + 269..], &[0, 0]);
    assert_eq!(decode_connect(d), Ok(Some(Version::V4_1)));
    // An old-style short ping.
    let short = B::default().put(b"Ping\0").message(0);
    assert_eq!(decode_connect(&short), Ok(None));
    assert!(decode_connect(&B::default().message(1)).is_err());
}

#[test]
fn hand_built_server_info_decodes() {
    let mut name = [0u8; 256];
    name[..6].copy_from_slice(b"Motive");
    let d = B::default()
        .put(&name)
        .put(&[3, 1, 0, 0])
        .put(&[0x04, 0x01, 0x00, 0x00]) // `04 01 00 00` = 4.1
        .u64(10_000_000)
        .u16(1511)
        .put(&[1])
        .put(&[239, 255, 42, 99])
        .message(1);
    assert_eq!(d.len(), 4 + 279);
    let info = decode_server_info(&d).unwrap();
    assert_eq!(info.app_name(), "Motive");
    assert_eq!(info.app_version, [3, 1, 0, 0]);
    assert_eq!(info.natnet_version, Version::V4_1);
    assert_eq!(
        info.details,
        Some(ServerDetails {
            high_res_clock_hz: 10_000_000,
            data_port: 1511,
            multicast: true,
            multicast_group: [239, 255, 42, 99],
        })
    );
    // The encoder writes the same bytes.
    let mut buf = [0u8; 512];
    let n = encode_server_info(&info, &mut buf).unwrap();
    assert_eq!(&buf[..n], &d[..]);
    // `sSender` only (264 bytes): no details.
    let short = B::default()
        .put(&name)
        .put(&[2, 2, 0, 0])
        .put(&[3, 0, 0, 0])
        .message(1);
    let info = decode_server_info(&short).unwrap();
    assert_eq!((info.natnet_version, info.details), (Version::V3_0, None));
    // Truncated.
    assert!(decode_server_info(&B::default().put(&name).message(1)).is_err());
    assert!(decode_server_info(&d[..100]).is_err());
}

#[test]
fn server_info_round_trips_without_details() {
    let info = ServerInfo::new("dronecine emulator", [0, 1, 0, 0], Version::V3_1);
    let mut buf = [0u8; 300];
    let n = encode_server_info(&info, &mut buf).unwrap();
    assert_eq!(n, 4 + 264);
    let back = decode_server_info(&buf[..n]).unwrap();
    assert_eq!(back, info);
    assert_eq!(back.app_name(), "dronecine emulator");
    // A name of 300 bytes keeps its NUL: cut to 255.
    let long = "m".repeat(300);
    assert_eq!(
        ServerInfo::new(&long, [0; 4], Version::V4_1)
            .app_name()
            .len(),
        255
    );
}

#[test]
fn split_message_reads_the_header() {
    assert_eq!(
        split_message(&[7, 0, 2, 0, 9, 9, 1]),
        Ok((7, &[9u8, 9][..]))
    );
    assert!(split_message(&[7, 0, 3, 0, 9, 9]).is_err());
    assert!(split_message(&[7, 0, 3]).is_err());
}

// ---------------------------------------------------------------------------------------
// Axes.

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-6
}

#[test]
fn y_up_maps_to_world_z_up() {
    // Motive (x, y up, z) → world (x, −z, y).
    let p = to_world(UpAxis::Y, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]).unwrap();
    assert_eq!(p.position_m, [1.0, -3.0, 2.0]);
    assert!(close(p.heading_rad, 0.0));
    // A turn of a about Motive's up axis (y) is a counter-clockwise heading a in the world.
    for a in [0.3f64, 1.2, -2.0, 3.0] {
        let (s, c) = (a / 2.0).sin_cos();
        let p = to_world(UpAxis::Y, [0.0; 3], [0.0, s as f32, 0.0, c as f32]).unwrap();
        assert!(close(p.heading_rad, a), "{a}: {}", p.heading_rad);
        // The world quaternion is the same turn about world z.
        let [x, y, z, w] = p.orientation_xyzw;
        assert!(close(x, 0.0) && close(y, 0.0) && close(z, s) && close(w, c));
    }
    // Motive's −z axis is world +y: a body whose nose points along Motive −z heads +π/2.
    // (Rotation about Motive y by +90° takes x to −z.)
    let (s, c) = (FRAC_PI_2 / 2.0).sin_cos();
    let p = to_world(UpAxis::Y, [0.0; 3], [0.0, s as f32, 0.0, c as f32]).unwrap();
    assert!(close(p.heading_rad, FRAC_PI_2));
}

#[test]
fn z_up_is_the_identity_and_tilt_does_not_turn_the_heading() {
    let p = to_world(UpAxis::Z, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]).unwrap();
    assert_eq!(p.position_m, [1.0, 2.0, 3.0]);
    let (s, c) = (0.7f64 / 2.0).sin_cos();
    let p = to_world(UpAxis::Z, [0.0; 3], [0.0, 0.0, s as f32, c as f32]).unwrap();
    assert!(close(p.heading_rad, 0.7));
    // Roll about the body's own x axis leaves the heading alone.
    let (s, c) = (0.3f64 / 2.0).sin_cos();
    let p = to_world(UpAxis::Z, [0.0; 3], [s as f32, 0.0, 0.0, c as f32]).unwrap();
    assert!(close(p.heading_rad, 0.0));
    // Heading of π stays π (the wrap of frames.rs), not −π.
    let p = to_world(UpAxis::Z, [0.0; 3], [0.0, 0.0, 1.0, 0.0]).unwrap();
    assert!(close(p.heading_rad, PI));
    // An unnormalised quaternion is normalised.
    let p = to_world(
        UpAxis::Z,
        [0.0; 3],
        [0.0, 0.0, 2.0 * s as f32, 2.0 * c as f32],
    )
    .unwrap();
    assert!(close(p.heading_rad, 0.3));
}

#[test]
fn unusable_poses_are_none() {
    assert!(to_world(UpAxis::Y, [0.0; 3], [0.0; 4]).is_none());
    assert!(to_world(UpAxis::Y, [f32::NAN, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).is_none());
    assert!(to_world(UpAxis::Y, [0.0; 3], [0.0, 0.0, f32::INFINITY, 1.0]).is_none());
    let mut b = RigidBody {
        id: 1,
        position_m: [1.0, 2.0, 3.0],
        orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
        mean_error_m: 0.0,
        params: 0,
    };
    assert!(b.body_pose(UpAxis::Y).is_none()); // not tracked
    b.params = 1;
    let pose = b.body_pose(UpAxis::Y).unwrap();
    assert_eq!(pose.position_m, [1.0, -3.0, 2.0]);
    assert_eq!(pose.heading_rad, 0.0);
}

// ---------------------------------------------------------------------------------------
// Round trips and random input.

fn any_body() -> impl Strategy<Value = RigidBody> {
    (
        any::<i32>(),
        any::<[u32; 3]>(),
        any::<[u32; 4]>(),
        any::<u32>(),
        any::<u16>(),
    )
        .prop_map(|(id, p, q, e, params)| RigidBody {
            id,
            position_m: p.map(f32::from_bits),
            orientation_xyzw: q.map(f32::from_bits),
            mean_error_m: f32::from_bits(e),
            params,
        })
}

fn body_bits(b: &RigidBody) -> (i32, [u32; 3], [u32; 4], u32, u16) {
    (
        b.id,
        b.position_m.map(f32::to_bits),
        b.orientation_xyzw.map(f32::to_bits),
        b.mean_error_m.to_bits(),
        b.params,
    )
}

fn any_version() -> impl Strategy<Value = Version> {
    prop_oneof![
        Just(Version::V3_0),
        Just(Version::V3_1),
        Just(Version::V4_0),
        Just(Version::V4_1)
    ]
}

proptest! {
    #[test]
    fn frame_round_trip(version in any_version(),
                        frame_number in any::<i32>(),
                        bodies in proptest::collection::vec(any_body(), 0..8),
                        names in proptest::collection::vec("[a-z_]{0,12}", 0..3),
                        markers in proptest::collection::vec(any::<[f32; 3]>(), 0..4),
                        labeled in 0usize..4,
                        stamps in any::<(u32, u32, u64, u64, u64, u32, u32, u16)>(),
                        timestamp_s in any::<f64>()) {
        let sets: Vec<MarkerSet<'_>> = names.iter().map(|n| MarkerSet { name: n, markers: &markers }).collect();
        let lm = vec![LabeledMarker { id: 3, position_m: [1.0, 2.0, 3.0], size_m: 0.01, params: 4, residual_m: 0.0 }; labeled];
        let out = FrameOut {
            frame_number,
            marker_sets: &sets,
            other_markers: &markers,
            rigid_bodies: &bodies,
            labeled_markers: &lm,
            timecode: stamps.0,
            timecode_sub: stamps.1,
            timestamp_s,
            camera_mid_exposure_ticks: stamps.2,
            camera_data_received_ticks: stamps.3,
            transmit_ticks: stamps.4,
            precision_timestamp_secs: stamps.5,
            precision_timestamp_frac_secs: stamps.6,
            params: stamps.7,
        };
        let mut buf = vec![0u8; 65_536];
        let n = encode_frame(&out, version, &mut buf).unwrap();
        let mut f = Frame::default();
        decode_frame(&buf[..n], version, &mut f).unwrap();
        prop_assert_eq!(f.frame_number, frame_number);
        prop_assert_eq!(f.marker_set_count as usize, sets.len());
        prop_assert_eq!(f.other_marker_count as usize, markers.len());
        prop_assert_eq!(f.labeled_marker_count as usize, labeled);
        prop_assert_eq!(f.rigid_bodies.iter().map(body_bits).collect::<Vec<_>>(),
                        bodies.iter().map(body_bits).collect::<Vec<_>>());
        prop_assert_eq!((f.timecode, f.timecode_sub), (stamps.0, stamps.1));
        prop_assert_eq!(f.timestamp_s.to_bits(), timestamp_s.to_bits());
        prop_assert_eq!((f.camera_mid_exposure_ticks, f.camera_data_received_ticks, f.transmit_ticks),
                        (stamps.2, stamps.3, stamps.4));
        let precise = version == Version::V4_1;
        prop_assert_eq!((f.precision_timestamp_secs, f.precision_timestamp_frac_secs),
                        if precise { (stamps.5, stamps.6) } else { (0, 0) });
        prop_assert_eq!(f.params, stamps.7);
        // Every cut of the payload is refused.
        for k in (0..n - 4).step_by(5) {
            prop_assert!(decode_frame_payload(&buf[4..4 + k], version, &mut f).is_err());
        }
    }

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400), version in any_version()) {
        let mut f = Frame::default();
        let _ = decode_frame(&bytes, version, &mut f);
        let _ = decode_frame_payload(&bytes, version, &mut f);
        let _ = decode_server_info(&bytes);
        let _ = decode_connect(&bytes);
        prop_assert!(f.rigid_bodies.len() <= bytes.len() / 38);
    }

    #[test]
    fn mutated_frames_never_panic(sized in any::<bool>(), flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..6)) {
        let mut d = hand_frame(sized);
        let n = d.len();
        for (i, b) in flips { d[4 + i % (n - 4)] = b; }
        let mut f = Frame::default();
        let v = if sized { Version::V4_1 } else { Version::V3_0 };
        let _ = decode_frame(&d, v, &mut f);
    }

    #[test]
    fn heading_is_the_yaw_of_any_rotation(yaw in -3.1f64..3.1, pitch in -1.2f64..1.2, roll in -1.2f64..1.2) {
        // q = Rz(yaw)·Ry(pitch)·Rx(roll) in Z-up: the heading is the yaw.
        let (sy, cy) = (yaw / 2.0).sin_cos();
        let (sp, cp) = (pitch / 2.0).sin_cos();
        let (sr, cr) = (roll / 2.0).sin_cos();
        let q = [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ];
        let p = to_world(UpAxis::Z, [0.0; 3], q.map(|v| v as f32)).unwrap();
        prop_assert!((p.heading_rad - yaw).abs() < 1e-5, "{} vs {}", p.heading_rad, yaw);
        // The same rotation streamed Y-up (axes mapped back) gives the same heading.
        let [x, y, z, w] = q;
        let p2 = to_world(UpAxis::Y, [0.0; 3], [x, z, -y, w].map(|v| v as f32)).unwrap();
        prop_assert!((p2.heading_rad - yaw).abs() < 1e-5);
    }
}
