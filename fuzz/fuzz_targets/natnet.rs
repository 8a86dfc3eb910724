//! Fuzz the NatNet codecs on arbitrary bytes (first byte picks the version 3.0/3.1/4.0/4.1):
//! frame, server-info and connect decoding never panic; a payload the frame decoder accepts
//! re-encodes (rigid bodies and suffix) to a frame that decodes to the same values, and
//! every accepted rigid body converts to the world frame without panicking.
#![no_main]

use dronecine_natnet::frame::{decode_connect, decode_frame, decode_frame_payload, decode_server_info, encode_frame, Frame, FrameOut, UpAxis, Version};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&v, body)) = data.split_first() else {
        return;
    };
    let version = [Version::V3_0, Version::V3_1, Version::V4_0, Version::V4_1][usize::from(v % 4)];
    let mut f = Frame::default();
    let _ = decode_frame(body, version, &mut f);
    let _ = decode_server_info(body);
    let _ = decode_connect(body);
    if decode_frame_payload(body, version, &mut f).is_ok() {
        for b in &f.rigid_bodies {
            for up in [UpAxis::Y, UpAxis::Z] {
                if let Some(p) = b.world_pose(up) {
                    assert!(
                        p.heading_rad.is_finite() && p.heading_rad.abs() <= std::f64::consts::PI
                    );
                }
            }
        }
        let out = FrameOut {
            frame_number: f.frame_number,
            rigid_bodies: &f.rigid_bodies,
            timecode: f.timecode,
            timecode_sub: f.timecode_sub,
            timestamp_s: f.timestamp_s,
            camera_mid_exposure_ticks: f.camera_mid_exposure_ticks,
            camera_data_received_ticks: f.camera_data_received_ticks,
            transmit_ticks: f.transmit_ticks,
            precision_timestamp_secs: f.precision_timestamp_secs,
            precision_timestamp_frac_secs: f.precision_timestamp_frac_secs,
            params: f.params,
            ..FrameOut::default()
        };
        let mut buf = vec![0u8; 70_000];
        let n = encode_frame(&out, version, &mut buf).unwrap();
        let mut again = Frame::default();
        decode_frame(&buf[..n], version, &mut again).unwrap();
        assert_eq!(
            format!("{:?}", again.rigid_bodies),
            format!("{:?}", f.rigid_bodies)
        );
        assert_eq!(again.frame_number, f.frame_number);
        assert_eq!(again.timestamp_s.to_bits(), f.timestamp_s.to_bits());
        assert_eq!(
            (
                again.transmit_ticks,
                again.params,
                again.precision_timestamp_secs
            ),
            (f.transmit_ticks, f.params, f.precision_timestamp_secs)
        );
    }
});
