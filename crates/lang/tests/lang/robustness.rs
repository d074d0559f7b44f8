//! The parser never panics: random bytes, random token soup, every truncation of the samples.

use lang::parse;

const SAMPLES: [&str; 4] = [
    include_str!("scenes/incline.lag"),
    include_str!("scenes/disk.lag"),
    include_str!("scenes/rod.lag"),
    include_str!("scenes/sketch.lag"),
];

/// A small deterministic generator (xorshift64*), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Parses and checks that every diagnostic span lies inside the source.
fn check(source: &str) {
    if let Err(diags) = parse(source) {
        assert!(!diags.is_empty());
        for d in diags {
            assert!(
                d.span.start <= d.span.end && d.span.end <= source.len(),
                "{d:?} in {source:?}"
            );
            assert!(source.is_char_boundary(d.span.start) && source.is_char_boundary(d.span.end));
        }
    }
}

#[test]
fn every_truncation_of_the_samples() {
    for sample in SAMPLES {
        for (i, _) in sample.char_indices() {
            check(&sample[..i]);
            check(&sample[i..]);
        }
    }
}

#[test]
fn random_bytes() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for _ in 0..3000 {
        let len = rng.below(80);
        let bytes: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
        check(&String::from_utf8_lossy(&bytes));
    }
}

#[test]
fn random_token_soup() {
    const TOKENS: [&str; 40] = [
        "scene",
        "param",
        "let",
        "coord",
        "body",
        "particle",
        "constraint",
        "gravity",
        "along",
        "force",
        "on",
        "show",
        "at",
        "start",
        "expect",
        "simulate",
        "x",
        "θ",
        "'",
        "''",
        "1",
        "2.5e-3",
        "(",
        ")",
        "[",
        "]",
        "{",
        "}",
        ",",
        ";",
        ":",
        "=",
        "+",
        "-",
        "*",
        "/",
        "^",
        "\n",
        "\"t\"",
        "# c\n",
    ];
    let mut rng = Rng(42);
    for _ in 0..3000 {
        let n = rng.below(30);
        let mut s = String::new();
        for _ in 0..n {
            s.push_str(TOKENS[rng.below(TOKENS.len())]);
            if rng.below(3) == 0 {
                s.push(' ');
            }
        }
        check(&s);
    }
}

#[test]
fn mutated_samples() {
    let mut rng = Rng(7);
    for _ in 0..500 {
        let sample = SAMPLES[rng.below(SAMPLES.len())];
        let mut bytes = sample.as_bytes().to_vec();
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(bytes.len());
            match rng.below(3) {
                0 => {
                    bytes.remove(at);
                }
                1 => {
                    const INSERT: &[u8] = b"()[]{},;:=+-*/^'\"#\n xa1";
                    bytes.insert(at, INSERT[rng.below(INSERT.len())]);
                }
                _ => bytes[at] = rng.next() as u8,
            }
        }
        check(&String::from_utf8_lossy(&bytes));
    }
}
