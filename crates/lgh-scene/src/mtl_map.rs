//! The options of an MTL texture statement (`map_Kd -s 2 2 1 -clamp on wood.png`): the
//! file name follows the options, which the MTL format defines as
//!
//! | option | arguments | read as |
//! | --- | --- | --- |
//! | `-clamp` | `on` / `off` | [`Wrap::Clamp`] in u and v (default repeat) |
//! | `-o` | u [v [w]] | offset of the texture coordinates |
//! | `-s` | u [v [w]] | scale of the texture coordinates |
//! | `-blendu`, `-blendv`, `-cc`, `-bm`, `-boost`, `-imfchan`, `-texres` | one | skipped |
//! | `-mm` | base gain | skipped |
//! | `-t` | u [v [w]] | skipped (turbulence) |
//!
//! The coordinates become uv * s + o, the reading of three.js's and Blender's importers
//! (`-s 2 2` repeats the texture twice across the surface).

use glam::Vec2;

use crate::texture::Wrap;

/// A texture statement's file name and the options lgh reads.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TextureMap<'a> {
    /// The file name, everything after the options (it may hold spaces).
    pub file: &'a str,
    /// How the texture reads beyond [0, 1].
    pub wrap: Wrap,
    /// `-o`'s u and v.
    pub offset: Vec2,
    /// `-s`'s u and v.
    pub scale: Vec2,
}

impl TextureMap<'_> {
    /// The coordinates `uv` mapped as the options say.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        uv * self.scale + self.offset
    }

    /// True if the options leave the coordinates as they are.
    pub fn keeps_coordinates(&self) -> bool {
        self.scale == Vec2::ONE && self.offset == Vec2::ZERO
    }
}

/// The options and file name of the statement's arguments (what follows `map_Kd`).
/// An option the format does not define, or one whose argument is missing, ends the options:
/// what follows is the file name, as a file whose name starts with `-` needs.
pub(crate) fn parse(arguments: &str) -> TextureMap<'_> {
    let mut map = TextureMap {
        file: "",
        wrap: Wrap::Repeat,
        offset: Vec2::ZERO,
        scale: Vec2::ONE,
    };
    let mut rest = arguments.trim_start();
    loop {
        let (word, after) = next_word(rest);
        let (taken, after) = match word {
            "-clamp" => match next_word(after) {
                ("on", a) => {
                    map.wrap = Wrap::Clamp;
                    (true, a)
                }
                ("off", a) => {
                    map.wrap = Wrap::Repeat;
                    (true, a)
                }
                _ => (false, after),
            },
            "-o" | "-s" | "-t" => match numbers(after) {
                (values, a) if !values.is_empty() => {
                    // An axis left out keeps the option's default (0 for -o, 1 for -s).
                    let uv =
                        |default: f32| Vec2::new(values[0], *values.get(1).unwrap_or(&default));
                    match word {
                        "-o" => map.offset = uv(0.0),
                        "-s" => map.scale = uv(1.0),
                        _ => {}
                    }
                    (true, a)
                }
                _ => (false, after),
            },
            "-mm" => match numbers(after) {
                (values, a) if values.len() >= 2 => (true, a),
                _ => (false, after),
            },
            "-blendu" | "-blendv" | "-cc" | "-bm" | "-boost" | "-imfchan" | "-texres" => {
                match next_word(after) {
                    ("", _) => (false, after),
                    (_, a) => (true, a),
                }
            }
            _ => (false, after),
        };
        if !taken {
            break;
        }
        rest = after.trim_start();
    }
    // The file name: what the options leave.
    map.file = rest.trim();
    map
}

/// The first whitespace-separated word of `s` and what follows it.
fn next_word(s: &str) -> (&str, &str) {
    let s = s.trim_start();
    let end = s.find(char::is_whitespace).unwrap_or(s.len());
    (&s[..end], &s[end..])
}

/// Up to three numbers at the start of `s` and what follows them.
fn numbers(mut s: &str) -> (Vec<f32>, &str) {
    let mut values = Vec::new();
    while values.len() < 3 {
        let (word, after) = next_word(s);
        match word.parse::<f32>() {
            Ok(v) if v.is_finite() => {
                values.push(v);
                s = after;
            }
            _ => break,
        }
    }
    (values, s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_name_is_the_file() {
        let m = parse("  textures/wood floor.png ");
        assert_eq!(m.file, "textures/wood floor.png");
        assert_eq!(m.wrap, Wrap::Repeat);
        assert!(m.keeps_coordinates());
    }

    #[test]
    fn options_before_the_name_are_read_or_skipped() {
        let m = parse("-blendu off -s 2 3 1 -o 0.5 -mm 0 1 -clamp on -imfchan l brick wall.jpg");
        assert_eq!(m.file, "brick wall.jpg");
        assert_eq!(m.wrap, Wrap::Clamp);
        assert_eq!(m.scale, Vec2::new(2.0, 3.0));
        assert_eq!(m.offset, Vec2::new(0.5, 0.0));
        assert_eq!(m.apply(Vec2::new(1.0, 1.0)), Vec2::new(2.5, 3.0));
        // An axis left out keeps its default; turbulence is skipped with its numbers.
        let m = parse("-s 4 -t 0.1 0.2 wood.png");
        assert_eq!((m.file, m.scale), ("wood.png", Vec2::new(4.0, 1.0)));
        assert_eq!(parse("-clamp off a.png").wrap, Wrap::Repeat);
    }

    /// An option the format does not know, or one without its argument, is where the
    /// file name starts.
    #[test]
    fn what_is_not_an_option_is_the_name() {
        assert_eq!(parse("-weird.png").file, "-weird.png");
        assert_eq!(parse("-clamp maybe.png").file, "-clamp maybe.png");
        assert_eq!(parse("-s x.png").file, "-s x.png");
        assert_eq!(parse("-clamp").file, "-clamp");
        assert_eq!(parse("").file, "");
    }

    proptest::proptest! {
        /// Any statement parses, and its file name is the end of it.
        #[test]
        fn any_statement_parses_to_a_suffix(s in "(-[a-z]{1,6} |[0-9.e+-]{1,4} |on |x\\.png|\\PC){0,12}") {
            let m = parse(&s);
            proptest::prop_assert!(s.trim_end().ends_with(m.file));
            proptest::prop_assert!(m.scale.is_finite() && m.offset.is_finite());
        }
    }
}
