//! The text encodings OBJ and MTL files come in. The formats say nothing of an encoding; the
//! files are mostly ASCII, but exporters of the 1990s and 2000s wrote names and comments in
//! ISO-8859-1 (Latin-1), and some tools write UTF-16 with a byte-order mark. The parser
//! (`tobj`) reads UTF-8, so such files are decoded first; the geometry does not depend on
//! it, only the names.

/// How a file's bytes were read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// UTF-8 (with or without a byte-order mark), or ASCII.
    Utf8,
    /// UTF-16 after a byte-order mark, little- or big-endian.
    Utf16,
    /// Not UTF-8 and no byte-order mark: every byte one character of ISO-8859-1.
    Latin1,
}

impl Encoding {
    /// The warning a file read this way deserves, if any.
    pub(crate) fn warning(self, what: &str) -> Option<String> {
        match self {
            Self::Utf8 => None,
            Self::Utf16 => Some(format!("{what} is UTF-16 text: read as such")),
            Self::Latin1 => Some(format!(
                "{what} is not UTF-8 text: read as ISO-8859-1 (Latin-1)"
            )),
        }
    }
}

/// Decodes `bytes` as text: a byte-order mark (UTF-8, UTF-16 little- or big-endian)
/// decides; else UTF-8 where the bytes are valid UTF-8, else ISO-8859-1.
///
/// # Errors
/// UTF-16 with an odd number of bytes or an unpaired surrogate.
pub(crate) fn decode(bytes: Vec<u8>) -> Result<(String, Encoding), &'static str> {
    let utf16 = |body: &[u8], from: fn([u8; 2]) -> u16| {
        if !body.len().is_multiple_of(2) {
            return Err("UTF-16 text with an odd number of bytes");
        }
        let units = body.chunks_exact(2).map(|c| from([c[0], c[1]]));
        char::decode_utf16(units)
            .collect::<Result<String, _>>()
            .map(|s| (s, Encoding::Utf16))
            .map_err(|_| "UTF-16 text with an unpaired surrogate")
    };
    match bytes.as_slice() {
        [0xEF, 0xBB, 0xBF, rest @ ..] => Ok(latin1_unless_utf8(rest.to_vec())),
        [0xFF, 0xFE, rest @ ..] => utf16(rest, u16::from_le_bytes),
        [0xFE, 0xFF, rest @ ..] => utf16(rest, u16::from_be_bytes),
        _ => Ok(latin1_unless_utf8(bytes)),
    }
}

/// The bytes as UTF-8 if they are, else as ISO-8859-1.
fn latin1_unless_utf8(bytes: Vec<u8>) -> (String, Encoding) {
    match String::from_utf8(bytes) {
        Ok(s) => (s, Encoding::Utf8),
        Err(e) => (
            e.into_bytes().into_iter().map(char::from).collect(),
            Encoding::Latin1,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encodings_are_told_apart() {
        let ascii = b"v 1 2 3\n".to_vec();
        assert_eq!(decode(ascii).unwrap(), ("v 1 2 3\n".into(), Encoding::Utf8));
        let bom = [&[0xEF, 0xBB, 0xBF][..], "g caf\u{e9}\n".as_bytes()].concat();
        assert_eq!(
            decode(bom).unwrap(),
            ("g caf\u{e9}\n".into(), Encoding::Utf8)
        );
        // "g café" in Latin-1: 0xE9 alone is not UTF-8.
        let latin1 = b"g caf\xe9\n".to_vec();
        assert_eq!(
            decode(latin1).unwrap(),
            ("g caf\u{e9}\n".into(), Encoding::Latin1)
        );
        let text = "v 1 2 3\ng \u{e9}\n";
        let be: Vec<u8> = [0xFE, 0xFF]
            .into_iter()
            .chain(text.encode_utf16().flat_map(u16::to_be_bytes))
            .collect();
        let le: Vec<u8> = [0xFF, 0xFE]
            .into_iter()
            .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
            .collect();
        assert_eq!(decode(be).unwrap(), (text.into(), Encoding::Utf16));
        assert_eq!(decode(le.clone()).unwrap(), (text.into(), Encoding::Utf16));
        assert!(decode(le[..le.len() - 1].to_vec()).is_err());
        assert!(decode(vec![0xFF, 0xFE, 0x00, 0xD8]).is_err());
    }
}
