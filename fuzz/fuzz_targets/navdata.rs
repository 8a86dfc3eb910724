//! Fuzz the AR.Drone codecs on arbitrary bytes: the navdata decoder (a packet it accepts
//! has a correct checksum, and what it decoded re-encodes to a packet that decodes to the
//! same fields) and the AT parser on the same bytes as a datagram (every line it accepts
//! re-encodes and parses back to the same command).
#![no_main]

use dronecine_ardrone::at::{self, AtEncoder, Datagram};
use dronecine_ardrone::navdata::{self, Navdata, NavdataWriter};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut nav = Navdata::default();
    if navdata::decode(data, &mut nav).is_ok() {
        assert_eq!(nav.checksum, navdata::checksum(&data[..data.len() - 8]));
        let mut buf = [0u8; navdata::NAVDATA_MAX_SIZE];
        let mut w = NavdataWriter::with_header(
            &mut buf,
            nav.header,
            nav.state,
            nav.sequence,
            nav.vision_defined,
        )
        .unwrap();
        if let Some(d) = &nav.demo {
            w.demo(d).unwrap();
        }
        if let Some(t) = nav.time {
            w.time(t).unwrap();
        }
        let n = w.finish().unwrap();
        let mut again = Navdata::default();
        navdata::decode(&buf[..n], &mut again).unwrap();
        assert_eq!(
            (
                again.header,
                again.state,
                again.sequence,
                again.vision_defined,
                again.time
            ),
            (
                nav.header,
                nav.state,
                nav.sequence,
                nav.vision_defined,
                nav.time
            )
        );
        assert_eq!(format!("{:?}", again.demo), format!("{:?}", nav.demo));
    }

    let mut enc = AtEncoder::new();
    let mut buf = [0u8; 2 * at::MAX_LINE_LEN];
    for line in at::parse_datagram(data).flatten() {
        let mut dg = Datagram::new(&mut buf);
        enc.push(&mut dg, &line.command).unwrap();
        let back = at::parse_datagram(dg.as_bytes()).next().unwrap().unwrap();
        assert_eq!(format!("{:?}", back.command), format!("{:?}", line.command));
    }
});
