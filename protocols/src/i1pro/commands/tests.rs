//! Requests and replies against the byte strings written out by hand from the documented
//! layouts (the README's table and example exchanges).

use super::*;
use crate::i1pro::timing::clocks;

fn out(request: u8, data: &[u8]) -> Transfer {
    Transfer::Out {
        setup: Setup {
            request_type: 0x40,
            request,
            value: 0,
            index: 0,
        },
        data: data.to_vec(),
    }
}

fn input(request: u8, length: u16) -> Transfer {
    Transfer::In {
        setup: Setup {
            request_type: 0xC0,
            request,
            value: 0,
            index: 0,
        },
        length,
    }
}

#[test]
fn reset_has_one_byte_on_rev_a_to_d_and_two_on_rev_e() {
    let r = Request::Reset { mask: RESET_NORMAL };
    assert_eq!(r.encode(Revision::AToD).unwrap(), out(0xCA, &[0x1F]));
    assert_eq!(r.encode(Revision::E).unwrap(), out(0xCA, &[0x1F, 0x00]));
}

#[test]
fn eeprom_read_of_8192_bytes_at_zero() {
    let r = Request::ReadEeprom {
        address: 0,
        length: 0x2000,
    };
    assert_eq!(
        r.encode(Revision::AToD).unwrap(),
        out(0xC4, &[0, 0, 0, 0, 0x20, 0, 0, 0])
    );
    let r = Request::ReadEeprom {
        address: 0x0001_2345,
        length: 0x4000,
    };
    assert_eq!(
        r.encode(Revision::E).unwrap(),
        out(0xC4, &[0, 1, 0x23, 0x45, 0x40, 0])
    );
}

#[test]
fn set_meas_params_for_a_quarter_second_dark_reading() {
    // 0.25 s / 68 µs = 3676.47 → 3676 = 0x0E5C; one reading; lamp off + normal gain = 0x06.
    let int_clocks = clocks("integration time", 0.25, 68e-6, 0xFFFF).unwrap();
    assert_eq!(int_clocks, 3676);
    let p = MeasParams {
        int_clocks: int_clocks as u16,
        lamp_clocks: 0,
        readings: 1,
        flags: flags::LAMP_OFF | flags::NORMAL_GAIN,
    };
    let t = Request::SetMeasParams(p).encode(Revision::AToD).unwrap();
    assert_eq!(t, out(0xC1, &[0x0E, 0x5C, 0, 0, 0, 1, 0x06, 0]));
    // 1.0 s / 68 µs = 14705.9 → 14706 = 0x3972.
    assert_eq!(clocks("t", 1.0, 68e-6, 0xFFFF).unwrap(), 0x3972);
    assert_eq!(MeasParams::parse(&p.encode()).unwrap(), p);
}

#[test]
fn parameterless_requests() {
    let a = Revision::AToD;
    let e = Revision::E;
    assert_eq!(Request::Trigger.encode(a).unwrap(), out(0xC0, &[]));
    assert_eq!(Request::GetMisc.encode(a).unwrap(), input(0xC9, 8));
    assert_eq!(Request::GetMeasParams.encode(a).unwrap(), input(0xC2, 8));
    assert_eq!(Request::SetClockMode(2).encode(a).unwrap(), out(0xCF, &[2]));
    assert_eq!(Request::GetClockMode.encode(a).unwrap(), input(0xD1, 6));
    assert_eq!(Request::GetEepromSize.encode(e).unwrap(), input(0xD9, 4));
    assert_eq!(Request::GetChipId.encode(e).unwrap(), input(0xD2, 8));
    assert_eq!(Request::GetChipId.encode(a).unwrap(), input(0xD2, 8));
    assert_eq!(Request::GetMeasChar.encode(e).unwrap(), input(0xD5, 16));
    assert_eq!(Request::GetUvVolts.encode(e).unwrap(), input(0xD8, 4));
    assert_eq!(Request::StopRuler.encode(e).unwrap(), out(0xD7, &[0, 0]));
    let end = Request::EndSwitchRead.encode(a).unwrap();
    assert_eq!(
        end,
        Transfer::Out {
            setup: Setup {
                request_type: 0x40,
                request: 0xD0,
                value: 3,
                index: 0
            },
            data: vec![0xFF, 0xFF, 0xFF, 0xFF, 0xFC, 0xEE, 0x12, 0x00],
        }
    );
}

#[test]
fn rev_e_measure_packs_three_u32_and_the_flags() {
    let p = MeasParamsE {
        int_clocks: 0x0001_B207,
        lamp_clocks: 0,
        readings: 3,
        flags: flags_e::LAMP,
    };
    let t = Request::MeasureE(p).encode(Revision::E).unwrap();
    assert_eq!(
        t,
        out(0xD4, &[0, 1, 0xB2, 7, 0, 0, 0, 0, 0, 0, 0, 3, 0x01, 0x00])
    );
}

#[test]
fn requests_of_the_other_revision_are_refused() {
    let e = Request::Trigger.encode(Revision::E).unwrap_err();
    assert_eq!(
        e,
        ControlRequestError::WrongRevision {
            request: "trigger measurement",
            revision: Revision::E
        }
    );
    assert!(Request::GetMeasChar.encode(Revision::AToD).is_err());
    let p = MeasParamsE {
        int_clocks: 1,
        lamp_clocks: 0,
        readings: 1,
        flags: 0,
    };
    assert!(Request::MeasureE(p).encode(Revision::AToD).is_err());
}

#[test]
fn every_request_decodes_to_itself() {
    let p = MeasParams {
        int_clocks: 0x1234,
        lamp_clocks: 7,
        readings: 9,
        flags: flags::SCAN,
    };
    let pe = MeasParamsE {
        int_clocks: 136,
        lamp_clocks: 2,
        readings: 70000,
        flags: flags_e::WAVELENGTH_LED,
    };
    let both = [
        Request::Reset { mask: RESET_POWER },
        Request::GetMisc,
        Request::ReadEeprom {
            address: 0x1000,
            length: 512,
        },
        Request::GetMeasParams,
        Request::SetClockMode(3),
        Request::GetClockMode,
        Request::EndSwitchRead,
        Request::GetChipId,
    ];
    for rev in [Revision::AToD, Revision::E] {
        let own: Vec<Request> = match rev {
            Revision::AToD => vec![Request::SetMeasParams(p), Request::Trigger],
            Revision::E => vec![
                Request::GetEepromSize,
                Request::GetMeasChar,
                Request::MeasureE(pe),
                Request::GetUvVolts,
                Request::StopRuler,
            ],
        };
        for r in both.iter().chain(own.iter()) {
            let t = r.encode(rev).unwrap();
            assert_eq!(Request::decode(&t, rev).unwrap(), *r, "{rev:?} {r:?}");
        }
    }
}

#[test]
fn malformed_transfers_are_errors() {
    assert_eq!(
        Request::decode(&out(0xEE, &[]), Revision::AToD).unwrap_err(),
        ControlRequestError::Unknown {
            request_type: 0x40,
            request: 0xEE
        }
    );
    // A Rev A–D EEPROM read is 8 bytes; 6 is the Rev E form.
    assert!(matches!(
        Request::decode(&out(0xC4, &[0, 0, 0, 0, 1, 0]), Revision::AToD),
        Err(ControlRequestError::BadData { .. })
    ));
    assert!(matches!(
        Request::decode(&out(0xC1, &[1, 2, 3]), Revision::AToD),
        Err(ControlRequestError::BadData { .. })
    ));
    assert!(matches!(
        Request::decode(&out(0xD4, &[0; 14]), Revision::AToD),
        Err(ControlRequestError::WrongRevision { .. })
    ));
}

proptest::proptest! {
    #[test]
    fn arbitrary_transfers_never_panic(
        request_type in proptest::prelude::any::<u8>(),
        request in proptest::prelude::any::<u8>(),
        data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..20),
    ) {
        let setup = Setup { request_type, request, value: 0, index: 0 };
        for rev in [Revision::AToD, Revision::E] {
            let _ = Request::decode(&Transfer::Out { setup, data: data.clone() }, rev);
            let _ = Request::decode(&Transfer::In { setup, length: data.len() as u16 }, rev);
        }
    }
}
