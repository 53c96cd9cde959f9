#![allow(clippy::unwrap_used)]
//! Property tests of the frame-range syntax shared by every command (`A..B` inclusive,
//! `A..=B`, `A-B`, a single `A`): what is written is what is read, a reversed range is refused
//! with a message that names it, and no text makes the parser panic.

use omnimvs_data::FrameRange;
use proptest::prelude::*;

proptest! {
    #[test]
    fn every_syntax_reads_the_same_range(a in 0u32..100_000, len in 0u32..100_000) {
        let b = a + len;
        let want = FrameRange { start: a, step: 1, end: b };
        for text in [format!("{a}..{b}"), format!("{a}..={b}"), format!("{a}-{b}"), format!(" {a} .. {b} ")] {
            prop_assert_eq!(text.parse::<FrameRange>().unwrap(), want, "{}", text);
        }
        // Display writes what FromStr reads.
        prop_assert_eq!(want.to_string().parse::<FrameRange>().unwrap(), want);
        prop_assert_eq!(want.indices().len() as u64, u64::from(len) + 1);
        prop_assert!(want.contains(a) && want.contains(b) && !want.contains(b + 1));
    }

    #[test]
    fn a_single_frame_is_a_range_of_one(a in any::<u32>()) {
        let range: FrameRange = a.to_string().parse().unwrap();
        prop_assert_eq!(range, FrameRange::inclusive(a, a));
    }

    #[test]
    fn a_reversed_range_is_refused_by_name(b in 0u32..1_000_000, gap in 1u32..1_000) {
        let a = b + gap;
        let text = format!("{a}..{b}");
        let err = text.parse::<FrameRange>().unwrap_err().to_string();
        prop_assert!(err.contains(&text) && err.contains("reversed"), "{}", err);
    }

    #[test]
    fn no_text_panics(text in "\\PC{0,12}") {
        if let Ok(range) = text.parse::<FrameRange>() {
            prop_assert!(range.start <= range.end);
        }
    }

    #[test]
    fn malformed_text_says_what_was_expected(text in "[a-z]{1,5}(\\.\\.[a-z0-9]{0,3})?") {
        let err = text.parse::<FrameRange>().unwrap_err().to_string();
        prop_assert!(err.contains("expected FIRST..LAST"), "{}", err);
    }
}
