//! The codecs on arbitrary input: any bytes decode to a message or an error, never a panic;
//! every message decoded encodes back to the same message; any text is an address or an
//! error.

use std::time::Instant;

use dronecine_crazyflie::crtp::{FromDrone, LogOps, Packet, ToDrone, MAX_PAYLOAD};
use dronecine_crazyflie::link::LinkState;
use dronecine_crazyflie::log::{Layout, Values, BLOCKS};
use dronecine_crazyflie::CrazyflieUrl;
use proptest::prelude::*;

/// A header of any port and channel, or of the ports the codecs read, more often.
fn header() -> impl Strategy<Value = u8> {
    prop_oneof![
        any::<u8>(),
        prop::sample::select(vec![
            0x0Cu8, 0x2F, 0x5C, 0x5D, 0x5E, 0x6D, 0x7C, 0x9D, 0xDC, 0xDD
        ]),
    ]
}

/// Bytes that are often packets of the known kinds: a header, then any payload.
fn datagram() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..40),
        (
            header(),
            prop::collection::vec(any::<u8>(), 0..=MAX_PAYLOAD)
        )
            .prop_map(|(h, mut p)| {
                p.insert(0, h);
                p
            }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn any_bytes_decode_or_are_refused_and_decoded_messages_round_trip(bytes in datagram()) {
        let Ok(packet) = Packet::from_bytes(&bytes) else {
            prop_assert!(bytes.is_empty() || bytes.len() > MAX_PAYLOAD + 1);
            return Ok(());
        };
        prop_assert_eq!(packet.as_bytes(), &bytes[..]);
        if let Ok(m) = ToDrone::decode(&packet) {
            if !matches!(m, ToDrone::Other { .. }) {
                // Its encoding is to the same port and channel, and decodes to a message
                // that encodes the same (bytes, not values: a NaN set-point is not equal to
                // itself).
                let again = m.encode().expect("a decoded message fits a packet");
                prop_assert_eq!((again.port(), again.channel()), (packet.port(), packet.channel()));
                let back = ToDrone::decode(&again).expect("its encoding decodes");
                prop_assert_eq!(back.encode().expect("again"), again, "{:?}", m);
            }
        }
        if let Ok(m) = FromDrone::decode(&packet) {
            if !matches!(m, FromDrone::Other { .. }) {
                let again = m.encode().expect("a decoded message fits a packet");
                prop_assert_eq!(FromDrone::decode(&again), Ok(m));
            }
        }
    }

    #[test]
    fn the_link_state_takes_any_datagram(datagrams in prop::collection::vec(datagram(), 1..20)) {
        let mut s = LinkState::default();
        let kinds = [7u8, 7, 7, 7, 7, 7];
        s.layouts[0] = Layout::new(&BLOCKS[0], &kinds);
        let now = Instant::now();
        for d in &datagrams {
            s.apply(d, now);
        }
        prop_assert_eq!(s.received + s.rejected, datagrams.len() as u64);
    }

    #[test]
    fn a_block_decodes_any_sample_or_refuses_it(
        kinds in prop::collection::vec(0u8..12, 4),
        data in prop::collection::vec(any::<u8>(), 0..30),
    ) {
        if let Some(layout) = Layout::new(&BLOCKS[1], &kinds) {
            let mut v = Values::default();
            let ok = layout.decode(&data, &mut v);
            prop_assert_eq!(ok, data.len() == layout.sample_len());
        }
    }

    #[test]
    fn log_ops_of_any_variables_fit_or_are_refused(vars in prop::collection::vec((1u8..9, any::<u16>()), 0..12)) {
        let mut buf = [0u8; 27];
        match LogOps::encode(&vars, &mut buf) {
            Ok(ops) => {
                prop_assert!(vars.len() <= LogOps::MAX);
                let back: Vec<u16> = ops.iter().map(|(_, id)| id).collect();
                let ids: Vec<u16> = vars.iter().map(|&(_, id)| id).collect();
                prop_assert_eq!(back, ids);
            }
            Err(_) => prop_assert!(vars.len() > LogOps::MAX),
        }
    }

    #[test]
    fn any_text_is_an_address_or_an_error(text in "(crazyflie\\+)?(radio|udp)?(://)?[0-9a-zA-Z/:.?=&\\[\\]]{0,30}") {
        if let Ok(u) = CrazyflieUrl::parse(&text) {
            prop_assert_eq!(CrazyflieUrl::parse(&u.to_string()), Ok(u));
        }
    }
}
