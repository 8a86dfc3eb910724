//! AR.Drone 2.0 codecs against the protocol: every verified constant, byte-exact AT
//! lines, the generic-command mapping and its signs, hand-built navdata packets (the
//! forum's bootstrap packet, a demo packet), rejection of bad packets, encoder → decoder
//! round trips, and no panic on truncated or random input.

use dronecine_ardrone::at::{
    self, parse_datagram, AtCommand, AtEncoder, AtError, AtLine, AtParseErrorKind, Datagram, Pcmd,
    PcmdLimits, MAX_LINE_LEN,
};
use dronecine_ardrone::navdata::{
    self, checksum, ControlState, Demo, DroneState, MajorState, NavTime, Navdata, NavdataError,
    NavdataSequence, NavdataWriter,
};
use dronecine_backend::frames::Command;
use dronecine_profile::Profile;
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------
// AT commands.

fn encode(cmds: &[AtCommand<'_>]) -> String {
    let mut buf = [0u8; 4096];
    let mut dg = Datagram::new(&mut buf);
    let mut enc = AtEncoder::new();
    for (i, c) in cmds.iter().enumerate() {
        assert_eq!(enc.push(&mut dg, c), Ok(i as u32 + 1));
    }
    String::from_utf8(dg.as_bytes().to_vec()).unwrap()
}

#[test]
fn verified_float_encodings() {
    // node-ar-drone's tests; 0 → 0.
    for (v, wire) in [
        (1.0f32, 1065353216),
        (-1.0, -1082130432),
        (0.5, 1056964608),
        (-0.5, -1090519040),
        (0.25, 1048576000),
        (-0.8, -1085485875),
        (0.0, 0),
    ] {
        assert_eq!(at::float_to_wire(v), wire, "{v}");
        assert_eq!(at::wire_to_float(wire), v);
    }
}

#[test]
fn ref_words_are_the_documented_ones() {
    // Land 290717696, take-off 290718208, emergency 290717952.
    assert_eq!(
        encode(&[AtCommand::LAND, AtCommand::TAKE_OFF, AtCommand::EMERGENCY]),
        "AT*REF=1,290717696\rAT*REF=2,290718208\rAT*REF=3,290717952\r"
    );
    assert_eq!(at::REF_BASE, 0x1154_0000);
    // Only bits 8 and 9 count (node-ar-drone sends REF without the legacy bits).
    assert!(at::ref_take_off(1 << 9) && !at::ref_emergency(1 << 9));
    assert!(at::ref_emergency(1 << 8) && !at::ref_take_off(1 << 8));
    assert!(!at::ref_take_off(290717696) && !at::ref_emergency(290717696));
    assert!(at::ref_take_off(290718208) && at::ref_emergency(290717952));
}

#[test]
fn every_command_byte_exact_with_one_global_counter() {
    let pcmd = Pcmd::progressive(-0.8, 0.5, 0.25, -1.0);
    let got = encode(&[
        AtCommand::Pcmd(pcmd),
        AtCommand::Comwdg,
        AtCommand::HOVER,
        AtCommand::Ftrim,
        AtCommand::Config {
            key: "general:navdata_demo",
            value: "TRUE",
        },
        AtCommand::ConfigIds {
            session: "ad1efdac",
            user: "992f7f4f",
            application: "510acf97",
        },
        AtCommand::ACK,
        AtCommand::PcmdMag {
            pcmd: Pcmd {
                flag: at::PCMD_PROGRESSIVE | at::PCMD_ABSOLUTE,
                ..pcmd
            },
            psi: 0.5,
            psi_accuracy: -0.5,
        },
        AtCommand::Calib { device: 0 },
        AtCommand::Ctrl { mode: 4, arg: 0 },
    ]);
    let want = "AT*PCMD=1,1,-1085485875,1056964608,1048576000,-1082130432\r\
                AT*COMWDG=2\r\
                AT*PCMD=3,0,0,0,0,0\r\
                AT*FTRIM=4\r\
                AT*CONFIG=5,\"general:navdata_demo\",\"TRUE\"\r\
                AT*CONFIG_IDS=6,\"ad1efdac\",\"992f7f4f\",\"510acf97\"\r\
                AT*CTRL=7,5,0\r\
                AT*PCMD_MAG=8,5,-1085485875,1056964608,1048576000,-1082130432,1056964608,-1090519040\r\
                AT*CALIB=9,0\r\
                AT*CTRL=10,4,0\r";
    assert_eq!(got, want);
}

#[test]
fn strings_needing_escapes_are_refused_without_using_a_seq() {
    let mut buf = [0u8; 256];
    let mut dg = Datagram::new(&mut buf);
    let mut enc = AtEncoder::new();
    for value in ["a\"b", "a\rb", "a\nb"] {
        let c = AtCommand::Config { key: "k:k", value };
        assert_eq!(enc.push(&mut dg, &c), Err(AtError::BadString));
        let c = AtCommand::ConfigIds {
            session: "s",
            user: value,
            application: "a",
        };
        assert_eq!(enc.push(&mut dg, &c), Err(AtError::BadString));
    }
    assert!(dg.is_empty());
    assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(1));
}

#[test]
fn line_limit_is_1024_bytes_with_the_cr() {
    // `AT*CONFIG=1,"` + key + `","v"` + `\r` = 19 + key.
    let fixed = "AT*CONFIG=1,\"\",\"v\"\r".len();
    let key_ok = "k".repeat(MAX_LINE_LEN - fixed);
    let key_long = "k".repeat(MAX_LINE_LEN - fixed + 1);
    let mut buf = vec![0u8; 4096];
    let mut dg = Datagram::new(&mut buf);
    let mut enc = AtEncoder::new();
    let c = AtCommand::Config {
        key: &key_long,
        value: "v",
    };
    assert_eq!(enc.push(&mut dg, &c), Err(AtError::LineTooLong));
    assert!(dg.is_empty());
    let c = AtCommand::Config {
        key: &key_ok,
        value: "v",
    };
    assert_eq!(enc.push(&mut dg, &c), Ok(1));
    assert_eq!(dg.len(), MAX_LINE_LEN);
    // A small buffer: full, not too long.
    let mut small = [0u8; 30];
    let mut dg = Datagram::new(&mut small);
    assert_eq!(enc.push(&mut dg, &c), Err(AtError::BufferFull));
}

#[test]
fn datagram_fills_then_refuses_and_clear_reuses_it() {
    // "AT*COMWDG=1\r" is 12 bytes: a 30-byte buffer takes two.
    let mut buf = [0u8; 30];
    let mut dg = Datagram::new(&mut buf);
    let mut enc = AtEncoder::new();
    assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(1));
    assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(2));
    assert_eq!(
        enc.push(&mut dg, &AtCommand::Comwdg),
        Err(AtError::BufferFull)
    );
    assert_eq!(dg.as_bytes(), b"AT*COMWDG=1\rAT*COMWDG=2\r");
    dg.clear();
    assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(3));
    enc.reset();
    assert_eq!(enc.push(&mut dg, &AtCommand::Comwdg), Ok(1));
    assert_eq!(dg.as_bytes(), b"AT*COMWDG=3\rAT*COMWDG=1\r");
}

fn ardrone2() -> PcmdLimits {
    PcmdLimits::from_profile(&Profile::builtin("ardrone2").unwrap().limits).unwrap()
}

#[test]
fn positive_generic_values_give_positive_pcmd_values() {
    // frames.rs and AT*PCMD use the same signs: nothing is negated.
    let l = ardrone2();
    let one = |c: Command| l.pcmd(&c);
    let p = one(Command {
        roll_rad: 0.05,
        ..Command::HOVER
    });
    assert!(p.roll > 0.0 && p.pitch == 0.0 && p.gaz == 0.0 && p.yaw == 0.0);
    let p = one(Command {
        pitch_rad: 0.05,
        ..Command::HOVER
    });
    assert!(p.pitch > 0.0 && p.roll == 0.0);
    let p = one(Command {
        vz_mps: 0.3,
        ..Command::HOVER
    });
    assert!(p.gaz > 0.0);
    let p = one(Command {
        yaw_rate_radps: 0.5,
        ..Command::HOVER
    });
    assert!(p.yaw > 0.0);
    let p = one(Command {
        roll_rad: -0.05,
        pitch_rad: -0.05,
        yaw_rate_radps: -0.5,
        vz_mps: -0.3,
    });
    assert!(p.roll < 0.0 && p.pitch < 0.0 && p.gaz < 0.0 && p.yaw < 0.0);
    assert_eq!(p.flag, at::PCMD_PROGRESSIVE);
}

#[test]
fn pcmd_values_are_fractions_of_the_limits_clamped() {
    let l = PcmdLimits::new(0.2, 0.8, 2.0).unwrap();
    let p = l.pcmd(&Command {
        roll_rad: 0.1,
        pitch_rad: -0.05,
        yaw_rate_radps: 0.5,
        vz_mps: 0.2,
    });
    assert_eq!(
        (p.roll, p.pitch, p.gaz, p.yaw),
        (0.5, -0.25, 0.25, 0.25),
        "{p:?}"
    );
    let p = l.pcmd(&Command {
        roll_rad: 3.0,
        pitch_rad: -3.0,
        yaw_rate_radps: 100.0,
        vz_mps: -9.0,
    });
    assert_eq!((p.roll, p.pitch, p.gaz, p.yaw), (1.0, -1.0, -1.0, 1.0));
    // Zero goes out as 0 (never the bits of −0.0).
    let p = l.pcmd(&Command {
        roll_rad: -0.0,
        ..Command::HOVER
    });
    assert_eq!(at::float_to_wire(p.roll), 0);
    assert_eq!(p.flag, at::PCMD_PROGRESSIVE);
}

#[test]
fn non_finite_commands_hover() {
    let l = ardrone2();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for i in 0..4 {
            let mut v = [0.1; 4];
            v[i] = bad;
            let c = Command {
                roll_rad: v[0],
                pitch_rad: v[1],
                yaw_rate_radps: v[2],
                vz_mps: v[3],
            };
            assert_eq!(l.pcmd(&c), Pcmd::HOVER);
        }
    }
    assert_eq!(
        encode(&[AtCommand::Pcmd(l.pcmd(&Command {
            roll_rad: f64::NAN,
            ..Command::HOVER
        }))]),
        "AT*PCMD=1,0,0,0,0,0\r"
    );
}

#[test]
fn startup_config_writes_the_profile_limits_in_firmware_units() {
    // ardrone2: 0.21 rad, 0.7 m/s = 700 mm/s, 1.75 rad/s (the firmware's indoor defaults,
    // config.ini units: rad, mm/s, rad/s).
    let lines = ardrone2().config_lines();
    let cmds: Vec<_> = lines.iter().map(|l| l.command()).collect();
    assert_eq!(
        encode(&cmds),
        "AT*CONFIG=1,\"control:euler_angle_max\",\"0.21\"\r\
         AT*CONFIG=2,\"control:control_vz_max\",\"700\"\r\
         AT*CONFIG=3,\"control:control_yaw\",\"1.75\"\r"
    );
    let outdoor =
        PcmdLimits::from_profile(&Profile::builtin("ardrone2-outdoor").unwrap().limits).unwrap();
    let values: Vec<_> = outdoor
        .config_lines()
        .iter()
        .map(|l| l.value().to_string())
        .collect();
    assert_eq!(values, ["0.35", "1000", "3.49"]);
    // The normalisation uses exactly what was sent.
    assert_eq!(outdoor.control_vz_max_mps(), 1.0);
}

#[test]
fn limits_outside_the_firmware_ranges_are_refused() {
    use at::{KEY_CONTROL_VZ_MAX, KEY_CONTROL_YAW, KEY_EULER_ANGLE_MAX};
    let bad = |t, v, y| PcmdLimits::new(t, v, y).unwrap_err();
    assert_eq!(
        bad(35f64.to_radians(), 0.7, 1.75),
        AtError::LimitOutOfRange(KEY_EULER_ANGLE_MAX)
    );
    assert_eq!(
        bad(0.0, 0.7, 1.75),
        AtError::LimitOutOfRange(KEY_EULER_ANGLE_MAX)
    );
    assert_eq!(
        bad(f64::NAN, 0.7, 1.75),
        AtError::LimitOutOfRange(KEY_EULER_ANGLE_MAX)
    );
    assert_eq!(
        bad(0.2, 0.1, 1.75),
        AtError::LimitOutOfRange(KEY_CONTROL_VZ_MAX)
    );
    assert_eq!(
        bad(0.2, 2.5, 1.75),
        AtError::LimitOutOfRange(KEY_CONTROL_VZ_MAX)
    );
    assert_eq!(
        bad(0.2, 0.7, 0.5),
        AtError::LimitOutOfRange(KEY_CONTROL_YAW)
    );
    assert_eq!(
        bad(0.2, 0.7, 7.0),
        AtError::LimitOutOfRange(KEY_CONTROL_YAW)
    );
    // The documented extremes are accepted (ardrone_aggressive.launch: 0.35 / 2000 / 6.11).
    assert!(PcmdLimits::new(0.52, 2.0, 6.11).is_ok());
    assert!(PcmdLimits::new(0.35, 0.2, 0.7).is_ok());
}

#[test]
fn parser_reads_hand_written_datagrams_with_any_terminator() {
    let dg = b"AT*REF=1,290718208\rAT*PCMD=2,1,0,-1082130432,0,1065353216\n\
               AT*FTRIM=3,\r\nAT*COMWDG=4\r\r\n\nAT*CONFIG=5,\"a,b\",\"TRUE\"\r\
               AT*CTRL=6,5,0";
    let lines: Vec<_> = parse_datagram(dg).collect::<Result<_, _>>().unwrap();
    assert_eq!(
        lines,
        [
            AtLine {
                seq: 1,
                command: AtCommand::TAKE_OFF
            },
            AtLine {
                seq: 2,
                command: AtCommand::Pcmd(Pcmd::progressive(0.0, -1.0, 0.0, 1.0))
            },
            AtLine {
                seq: 3,
                command: AtCommand::Ftrim
            },
            AtLine {
                seq: 4,
                command: AtCommand::Comwdg
            },
            AtLine {
                seq: 5,
                command: AtCommand::Config {
                    key: "a,b",
                    value: "TRUE"
                }
            },
            AtLine {
                seq: 6,
                command: AtCommand::ACK
            },
        ]
    );
    // node-ar-drone's REF without the legacy bits.
    let l = parse_datagram(b"AT*REF=0,512\r").next().unwrap().unwrap();
    assert_eq!(l.command, AtCommand::Ref { input: 512 });
}

#[test]
fn parser_rejects_bad_lines_and_goes_on() {
    use AtParseErrorKind as K;
    let cases: &[(&[u8], K)] = &[
        (b"XX*REF=1,0", K::NoPrefix),
        (b"AT*COMWDG", K::NoSeq),
        (b"AT*COMWDG=", K::NoSeq),
        (b"AT*COMWDG=-1", K::BadSeq),
        (b"AT*COMWDG=4294967296", K::BadSeq),
        (b"AT*LED=1,0,0,0", K::UnknownCommand),
        (b"AT*REF=1", K::ArgCount),
        (b"AT*REF=1,2,3", K::ArgCount),
        (b"AT*REF=1,0x10", K::BadInt),
        (b"AT*REF=1,2147483648", K::BadInt),
        (b"AT*PCMD=1,1,0,0,0", K::ArgCount),
        (b"AT*PCMD=1,1,0.5,0,0,0", K::BadInt),
        (b"AT*CONFIG=1,\"a\",b", K::BadString),
        (b"AT*CONFIG=1,\"a\",\"b", K::BadString),
        (b"AT*CONFIG=1,\"a\"x,\"b\"", K::BadString),
        (b"AT*CONFIG=1,\"\xff\",\"b\"", K::BadString),
        (b"AT*CONFIG=1,\"a\"", K::ArgCount),
        (b"AT*COMWDG=1,5", K::ArgCount),
    ];
    for (line, kind) in cases {
        let mut dg = line.to_vec();
        dg.extend_from_slice(b"\rAT*COMWDG=9\r");
        let got: Vec<_> = parse_datagram(&dg).collect();
        assert_eq!(got.len(), 2, "{}", String::from_utf8_lossy(line));
        assert_eq!(
            got[0].map_err(|e| (e.kind, e.line)),
            Err((*kind, 0)),
            "{}",
            String::from_utf8_lossy(line)
        );
        assert_eq!(got[1].unwrap().seq, 9);
    }
    // Over 1024 bytes with the terminator.
    let long = format!("AT*CONFIG=1,\"{}\",\"v\"", "k".repeat(1024));
    let e = parse_datagram(long.as_bytes()).next().unwrap().unwrap_err();
    assert_eq!(e.kind, K::LineTooLong);
}

fn any_str() -> impl Strategy<Value = String> {
    "[ -!#-~]{0,20}" // printable ASCII without '"'
}

#[derive(Clone, Debug)]
enum OwnedCmd {
    Ref(u32),
    Pcmd(i32, [u32; 4]),
    PcmdMag(i32, [u32; 6]),
    Ftrim,
    Config(String, String),
    ConfigIds(String, String, String),
    Comwdg,
    Ctrl(i32, i32),
    Calib(i32),
}

impl OwnedCmd {
    fn borrow(&self) -> AtCommand<'_> {
        let p = |flag, v: &[u32]| Pcmd {
            flag,
            roll: f32::from_bits(v[0]),
            pitch: f32::from_bits(v[1]),
            gaz: f32::from_bits(v[2]),
            yaw: f32::from_bits(v[3]),
        };
        match self {
            OwnedCmd::Ref(i) => AtCommand::Ref { input: *i },
            OwnedCmd::Pcmd(f, v) => AtCommand::Pcmd(p(*f, v)),
            OwnedCmd::PcmdMag(f, v) => AtCommand::PcmdMag {
                pcmd: p(*f, v),
                psi: f32::from_bits(v[4]),
                psi_accuracy: f32::from_bits(v[5]),
            },
            OwnedCmd::Ftrim => AtCommand::Ftrim,
            OwnedCmd::Config(k, v) => AtCommand::Config { key: k, value: v },
            OwnedCmd::ConfigIds(s, u, a) => AtCommand::ConfigIds {
                session: s,
                user: u,
                application: a,
            },
            OwnedCmd::Comwdg => AtCommand::Comwdg,
            OwnedCmd::Ctrl(m, a) => AtCommand::Ctrl { mode: *m, arg: *a },
            OwnedCmd::Calib(d) => AtCommand::Calib { device: *d },
        }
    }
}

fn any_cmd() -> impl Strategy<Value = OwnedCmd> {
    prop_oneof![
        any::<u32>().prop_map(OwnedCmd::Ref),
        (any::<i32>(), any::<[u32; 4]>()).prop_map(|(f, v)| OwnedCmd::Pcmd(f, v)),
        (any::<i32>(), any::<[u32; 6]>()).prop_map(|(f, v)| OwnedCmd::PcmdMag(f, v)),
        Just(OwnedCmd::Ftrim),
        (any_str(), any_str()).prop_map(|(k, v)| OwnedCmd::Config(k, v)),
        (any_str(), any_str(), any_str()).prop_map(|(s, u, a)| OwnedCmd::ConfigIds(s, u, a)),
        Just(OwnedCmd::Comwdg),
        (any::<i32>(), any::<i32>()).prop_map(|(m, a)| OwnedCmd::Ctrl(m, a)),
        any::<i32>().prop_map(OwnedCmd::Calib),
    ]
}

/// Bitwise equality (floats may be NaN).
fn same(a: &AtCommand<'_>, b: &AtCommand<'_>) -> bool {
    format!("{a:?}") == format!("{b:?}")
        && match (a, b) {
            (AtCommand::Pcmd(x), AtCommand::Pcmd(y)) => pcmd_bits(x) == pcmd_bits(y),
            (
                AtCommand::PcmdMag {
                    pcmd: x,
                    psi: p1,
                    psi_accuracy: a1,
                },
                AtCommand::PcmdMag {
                    pcmd: y,
                    psi: p2,
                    psi_accuracy: a2,
                },
            ) => {
                pcmd_bits(x) == pcmd_bits(y)
                    && p1.to_bits() == p2.to_bits()
                    && a1.to_bits() == a2.to_bits()
            }
            _ => true,
        }
}

fn pcmd_bits(p: &Pcmd) -> [u32; 5] {
    [
        p.flag as u32,
        p.roll.to_bits(),
        p.pitch.to_bits(),
        p.gaz.to_bits(),
        p.yaw.to_bits(),
    ]
}

proptest! {
    #[test]
    fn at_encoder_parser_round_trip(cmds in proptest::collection::vec(any_cmd(), 1..12)) {
        let mut buf = vec![0u8; 8192];
        let mut dg = Datagram::new(&mut buf);
        let mut enc = AtEncoder::new();
        let mut seqs = Vec::new();
        for c in &cmds {
            seqs.push(enc.push(&mut dg, &c.borrow()).unwrap());
        }
        // Seqs increase by one from the first.
        for w in seqs.windows(2) { prop_assert_eq!(w[1], w[0] + 1); }
        let parsed: Vec<_> = parse_datagram(dg.as_bytes()).collect::<Result<_, _>>().unwrap();
        prop_assert_eq!(parsed.len(), cmds.len());
        for ((line, c), seq) in parsed.iter().zip(&cmds).zip(&seqs) {
            prop_assert_eq!(line.seq, *seq);
            prop_assert!(same(&line.command, &c.borrow()), "{:?} vs {:?}", line.command, c);
        }
    }

    #[test]
    fn at_parser_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let n = parse_datagram(&bytes).count();
        prop_assert!(n <= bytes.len());
    }

    #[test]
    fn at_parser_survives_mutated_valid_lines(cmds in proptest::collection::vec(any_cmd(), 1..4),
                                              flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..6)) {
        let mut buf = vec![0u8; 4096];
        let mut dg = Datagram::new(&mut buf);
        let mut enc = AtEncoder::new();
        for c in &cmds { enc.push(&mut dg, &c.borrow()).unwrap(); }
        let mut bytes = dg.as_bytes().to_vec();
        for (i, b) in flips { let n = bytes.len(); bytes[i % n] = b; }
        for r in parse_datagram(&bytes) { let _ = r; }
    }

    #[test]
    fn pcmd_mapping_is_bounded_and_sign_preserving(r in -1.0f64..1.0, p in -1.0f64..1.0, y in -10.0f64..10.0, v in -3.0f64..3.0) {
        let l = ardrone2();
        let out = l.pcmd(&Command { roll_rad: r, pitch_rad: p, yaw_rate_radps: y, vz_mps: v });
        for (o, i) in [(out.roll, r), (out.pitch, p), (out.yaw, y), (out.gaz, v)] {
            prop_assert!((-1.0..=1.0).contains(&o));
            prop_assert!(o == 0.0 || (o > 0.0) == (i > 0.0));
        }
        // Inside the limits the fraction is exact (to f32).
        if r.abs() < l.euler_angle_max_rad() {
            prop_assert!((f64::from(out.roll) - r / l.euler_angle_max_rad()).abs() < 1e-6);
        }
    }
}

// ---------------------------------------------------------------------------------------
// Navdata, hand-built.

/// A little-endian byte builder for hand-written packets (independent of the encoder).
#[derive(Default)]
struct B(Vec<u8>);

impl B {
    fn u16(mut self, v: u16) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn u32(mut self, v: u32) -> Self {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn f32(self, v: f32) -> Self {
        self.u32(v.to_bits())
    }
    fn zeros(mut self, n: usize) -> Self {
        self.0.resize(self.0.len() + n, 0);
        self
    }
    /// Appends the checksum option: sum of every byte so far.
    fn cks(self) -> Self {
        let s = self.0.iter().map(|&b| b as u32).sum::<u32>();
        self.u16(0xFFFF).u16(8).u32(s)
    }
}

#[test]
fn forum_bootstrap_packet_decodes() {
    // The 24-byte bootstrap packet from the Parrot forum.
    let p = [
        0x88, 0x77, 0x66, 0x55, 0x10, 0x0c, 0x80, 0x4f, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0xff, 0xff, 0x08, 0x00, 0xa6, 0x02, 0x00, 0x00,
    ];
    let mut nav = Navdata::default();
    navdata::decode(&p, &mut nav).unwrap();
    assert_eq!(nav.header, navdata::NAVDATA_HEADER);
    assert_eq!(nav.state, DroneState(0x4F80_0C10));
    assert_eq!(nav.sequence, 1);
    assert_eq!(nav.checksum, 0x2A6);
    assert_eq!(checksum(&p[..16]), 0x2A6);
    assert!(nav.state.bootstrap() && !nav.state.flying() && nav.demo.is_none());
    // 0x4F800C10: bits 4, 10, 11, 23, 24–27 and 30 (no client has sent a command yet).
    assert_eq!(
        nav.state.flags().collect::<Vec<_>>(),
        [
            "altitude_control_active",
            "navdata_demo",
            "navdata_bootstrap",
            "pic_version_ok",
            "atcodec_thread_on",
            "navdata_thread_on",
            "video_thread_on",
            "acquisition_thread_on",
            "com_watchdog",
        ]
    );
}

fn demo_packet() -> Vec<u8> {
    B::default()
        .u32(0x5566_7788)
        .u32(0x8000_0001 | 1 << 10) // flying, navdata demo, emergency
        .u32(4711)
        .u32(1)
        // Demo option: tag 0, size 148.
        .u16(0)
        .u16(148)
        .u32((4 << 16) | 8) // HOVERING / LOST_COM
        .u32(87)
        .f32(-1500.0) // θ mdeg
        .f32(2500.0) // φ
        .f32(-90000.0) // ψ
        .u32(1234) // altitude mm
        .f32(100.0)
        .f32(-200.0)
        .f32(30.0)
        .u32(99)
        .zeros(148 - 44)
        // An option this decoder does not know (vision_detect, 16), 12 bytes.
        .u16(16)
        .u16(12)
        .u32(0xDEAD_BEEF)
        .u32(7)
        // Time option: 3 s, 250000 µs.
        .u16(1)
        .u16(8)
        .u32((3 << 21) | 250_000)
        .cks()
        .0
}

#[test]
fn hand_built_demo_packet_decodes_in_full() {
    let p = demo_packet();
    assert_eq!(p.len(), 16 + 148 + 12 + 8 + 8);
    let mut nav = Navdata::default();
    navdata::decode(&p, &mut nav).unwrap();
    assert_eq!(nav.sequence, 4711);
    assert_eq!(nav.vision_defined, 1);
    assert!(nav.state.flying() && nav.state.emergency());
    assert_eq!(
        nav.state.flags().collect::<Vec<_>>(),
        ["flying", "navdata_demo", "emergency"]
    );
    let d = nav.demo.unwrap();
    assert_eq!(
        d.ctrl_state,
        ControlState {
            major: MajorState::Hovering,
            minor: 8
        }
    );
    assert_eq!(d.battery_percent, 87);
    assert!((d.pitch_deg() + 1.5).abs() < 1e-12);
    assert!((d.roll_rad() - 2.5f64.to_radians()).abs() < 1e-12);
    assert!((d.yaw_rad() + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert_eq!(d.altitude_m(), 1.234);
    assert_eq!(d.velocity_mps(), [0.1, -0.2, 0.03]);
    assert_eq!(d.num_frames, 99);
    assert_eq!(nav.time, Some(NavTime::from_parts(3, 250_000)));
    assert_eq!(nav.time.unwrap().as_secs_f64(), 3.25);
    assert_eq!(nav.skipped_options, 1);
    assert_eq!(nav.options_seen, 1 | 1 << 1 | 1 << 16);
}

#[test]
fn alternative_header_accepted_others_refused() {
    let mut p = demo_packet();
    let mut nav = Navdata::default();
    p[0] = 0x89;
    // The checksum covers the header: rebuild it.
    let n = p.len();
    let s = checksum(&p[..n - 8]);
    p[n - 4..].copy_from_slice(&s.to_le_bytes());
    navdata::decode(&p, &mut nav).unwrap();
    assert_eq!(nav.header, navdata::NAVDATA_HEADER_ALT);
    p[0] = 0x87;
    assert_eq!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::BadHeader(0x5566_7787))
    );
}

#[test]
fn checksum_mismatch_is_rejected_and_output_untouched() {
    let good = demo_packet();
    let mut nav = Navdata::default();
    for i in [0usize, 5, 20, 100, good.len() - 9, good.len() - 1] {
        let mut p = good.clone();
        p[i] ^= 0x01;
        let r = navdata::decode(&p, &mut nav);
        // (Byte 0 flips 0x88 to 0x89, the alternative header: still a checksum error.)
        assert!(
            matches!(r, Err(NavdataError::ChecksumMismatch { .. })),
            "{i}: {r:?}"
        );
    }
    assert_eq!(nav, Navdata::default());
}

#[test]
fn bad_option_sizes_are_rejected() {
    let base = || B::default().u32(0x5566_7788).u32(0).u32(2).u32(0);
    let mut nav = Navdata::default();
    // Size under 4.
    let p = base().u16(16).u16(3).zeros(4).cks().0;
    assert!(matches!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::BadOptionSize { size: 3, .. })
    ));
    // Size 0 (would loop forever if accepted).
    let p = base().u16(16).u16(0).cks().0;
    assert!(matches!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::BadOptionSize { size: 0, .. })
    ));
    // Size past the end.
    let p = base().u16(16).u16(200).zeros(8).cks().0;
    assert!(matches!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::BadOptionSize { size: 200, .. })
    ));
    // Demo too short for its fields.
    let p = base().u16(0).u16(40).zeros(36).cks().0;
    assert_eq!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::BadKnownOptionSize { tag: 0, size: 40 })
    );
    // No checksum.
    let p = base().u16(16).u16(8).zeros(4).0;
    assert_eq!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::MissingChecksum)
    );
    // Bytes after the checksum.
    let mut p = base().cks().0;
    p.extend_from_slice(&[16, 0, 4, 0]);
    assert_eq!(
        navdata::decode(&p, &mut nav),
        Err(NavdataError::DataAfterChecksum)
    );
    // Over 4096 bytes.
    let p = base().u16(16).u16(4084).zeros(4080).cks().0;
    assert_eq!(p.len(), 4108);
    assert_eq!(navdata::decode(&p, &mut nav), Err(NavdataError::TooLarge));
    // Header only, and shorter.
    assert_eq!(
        navdata::decode(&base().0, &mut nav),
        Err(NavdataError::MissingChecksum)
    );
    assert_eq!(
        navdata::decode(&base().0[..15], &mut nav),
        Err(NavdataError::Truncated)
    );
}

#[test]
fn every_truncation_is_an_error() {
    let p = demo_packet();
    let mut nav = Navdata::default();
    for k in 0..p.len() {
        assert!(navdata::decode(&p[..k], &mut nav).is_err(), "prefix {k}");
    }
    assert_eq!(nav, Navdata::default());
}

#[test]
fn writer_matches_the_hand_built_packet_byte_for_byte() {
    let mut buf = [0u8; 4096];
    let mut w = NavdataWriter::new(&mut buf, DroneState(0x8000_0401), 4711, 1).unwrap();
    w.demo(&Demo {
        ctrl_state: ControlState::from_raw((4 << 16) | 8),
        battery_percent: 87,
        theta_mdeg: -1500.0,
        phi_mdeg: 2500.0,
        psi_mdeg: -90000.0,
        altitude_mm: 1234,
        vx_mmps: 100.0,
        vy_mmps: -200.0,
        vz_mmps: 30.0,
        num_frames: 99,
    })
    .unwrap();
    w.option(16, &[0xEF, 0xBE, 0xAD, 0xDE, 7, 0, 0, 0]).unwrap();
    w.time(NavTime::from_parts(3, 250_000)).unwrap();
    let n = w.finish().unwrap();
    assert_eq!(&buf[..n], &demo_packet()[..]);
}

#[test]
fn control_state_split() {
    for (raw, major, minor) in [
        (0x0003_0000, MajorState::Flying, 0),
        (0x0004_0008, MajorState::Hovering, 8),
        (0x0006_0001, MajorState::TransTakeoff, 1),
        (0x0008_0002, MajorState::TransLanding, 2),
        (0x0002_0000, MajorState::Landed, 0),
        (0x002A_0003, MajorState::Unknown(42), 3),
    ] {
        let c = ControlState::from_raw(raw);
        assert_eq!((c.major, c.minor), (major, minor));
        assert_eq!(c.raw(), raw);
    }
}

#[test]
fn sequence_rule_follows_the_sdk_client() {
    let mut s = NavdataSequence::new();
    let ok = DroneState(0);
    assert!(s.accept(1, ok));
    assert!(s.accept(2, ok));
    assert!(s.accept(5, ok)); // gaps are fine
    assert!(!s.accept(5, ok)); // duplicate
    assert!(!s.accept(4, ok)); // late: dropped, and becomes the last seen
    assert!(s.accept(6, ok));
    // Drone rebooted: back to 1. One packet is dropped, then the stream is followed.
    assert!(!s.accept(1, ok));
    assert!(s.accept(2, ok));
    // Com watchdog: the drone restarts numbering; the client resets before comparing.
    assert!(s.accept(3, ok));
    assert!(s.accept(1, DroneState(DroneState::COM_WATCHDOG)));
    // Wrap-around: one dropped, then followed.
    let mut s = NavdataSequence::new();
    assert!(s.accept(u32::MAX, ok));
    assert!(!s.accept(0, ok));
    assert!(s.accept(1, ok));
    // Reset (read timeout): anything from 1 on.
    s.reset();
    assert!(s.accept(1, ok));
    assert_eq!(s.last(), 1);
}

fn any_demo() -> impl Strategy<Value = Demo> {
    (
        any::<u32>(),
        any::<u32>(),
        any::<[u32; 3]>(),
        any::<i32>(),
        any::<[u32; 3]>(),
        any::<u32>(),
    )
        .prop_map(|(cs, bat, ang, alt, v, nf)| Demo {
            ctrl_state: ControlState::from_raw(cs),
            battery_percent: bat,
            theta_mdeg: f32::from_bits(ang[0]),
            phi_mdeg: f32::from_bits(ang[1]),
            psi_mdeg: f32::from_bits(ang[2]),
            altitude_mm: alt,
            vx_mmps: f32::from_bits(v[0]),
            vy_mmps: f32::from_bits(v[1]),
            vz_mmps: f32::from_bits(v[2]),
            num_frames: nf,
        })
}

fn demo_bits(d: &Demo) -> [u32; 10] {
    [
        d.ctrl_state.raw(),
        d.battery_percent,
        d.theta_mdeg.to_bits(),
        d.phi_mdeg.to_bits(),
        d.psi_mdeg.to_bits(),
        d.altitude_mm as u32,
        d.vx_mmps.to_bits(),
        d.vy_mmps.to_bits(),
        d.vz_mmps.to_bits(),
        d.num_frames,
    ]
}

proptest! {
    #[test]
    fn navdata_round_trip(state in any::<u32>(), seq in any::<u32>(), vision in any::<u32>(),
                          demo in proptest::option::of(any_demo()),
                          time in proptest::option::of(any::<u32>()),
                          extra in proptest::collection::vec((2u16..0xFFFE, proptest::collection::vec(any::<u8>(), 0..64)), 0..5)) {
        let mut buf = [0u8; 4096];
        let mut w = NavdataWriter::new(&mut buf, DroneState(state), seq, vision).unwrap();
        for (tag, payload) in &extra { w.option(*tag, payload).unwrap(); }
        if let Some(d) = &demo { w.demo(d).unwrap(); }
        if let Some(t) = time { w.time(NavTime(t)).unwrap(); }
        let n = w.finish().unwrap();
        let mut nav = Navdata::default();
        navdata::decode(&buf[..n], &mut nav).unwrap();
        prop_assert_eq!(nav.state, DroneState(state));
        prop_assert_eq!(nav.sequence, seq);
        prop_assert_eq!(nav.vision_defined, vision);
        prop_assert_eq!(nav.demo.map(|d| demo_bits(&d)), demo.map(|d| demo_bits(&d)));
        prop_assert_eq!(nav.time, time.map(NavTime));
        prop_assert_eq!(usize::from(nav.skipped_options), extra.len());
        prop_assert_eq!(nav.checksum, checksum(&buf[..n - 8]));
        // Every strict prefix is refused.
        for k in (0..n).step_by(7) {
            prop_assert!(navdata::decode(&buf[..k], &mut Navdata::default()).is_err());
        }
    }

    #[test]
    fn navdata_random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let mut nav = Navdata::default();
        let _ = navdata::decode(&bytes, &mut nav);
    }

    #[test]
    fn navdata_random_options_never_panic(body in proptest::collection::vec(any::<u8>(), 0..300), fix_cks in any::<bool>()) {
        // A valid header, random options, optionally a correct checksum over them.
        let mut p = B::default().u32(0x5566_7788).u32(0).u32(3).u32(0).0;
        p.extend_from_slice(&body);
        if fix_cks { p = B(p).cks().0; }
        let mut nav = Navdata::default();
        if navdata::decode(&p, &mut nav).is_ok() {
            prop_assert_eq!(nav.checksum, checksum(&p[..p.len() - 8]));
        }
    }
}
