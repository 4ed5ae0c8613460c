//! Text encodings of scene files as exporters write them.
//!
//! - [`decode`]: the bytes a parser reads. A UTF-8 byte-order mark is dropped; a UTF-16 file
//!   (little- or big-endian, recognised by its byte-order mark, as Windows tools write it) is
//!   converted to UTF-8, unpaired surrogates becoming U+FFFD; anything else is passed through
//!   as bytes, so lines, numbers and comments read the same whatever the encoding.
//! - [`name`]: a name or file name. Valid UTF-8 is taken as it is; anything else is read as
//!   Latin-1 (ISO 8859-1, what older exporters such as 3ds Max write), whose 256 byte values map
//!   one to one onto U+0000–U+00FF, so two different names never decode to the same string
//!   (lossy UTF-8 would turn both `Mat\xE9` and `Mat\xE8` into `Mat\u{FFFD}`).
use std::borrow::Cow;

const UTF8_BOM: [u8; 3] = [0xEF, 0xBB, 0xBF];
const UTF16_LE_BOM: [u8; 2] = [0xFF, 0xFE];
const UTF16_BE_BOM: [u8; 2] = [0xFE, 0xFF];

/// The file's text as UTF-8 (or raw) bytes; see the module doc.
pub fn decode(bytes: &[u8]) -> Cow<'_, [u8]> {
    if let Some(rest) = bytes.strip_prefix(&UTF8_BOM) {
        return Cow::Borrowed(rest);
    }
    let utf16 = |rest: &[u8], unit: fn([u8; 2]) -> u16| {
        // An odd trailing byte cannot be a UTF-16 unit: it becomes U+FFFD like other damage.
        let units = rest.chunks(2).map(|c| if c.len() == 2 { unit([c[0], c[1]]) } else { 0xFFFD });
        Cow::Owned(char::decode_utf16(units).map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER)).collect::<String>().into_bytes())
    };
    if let Some(rest) = bytes.strip_prefix(&UTF16_LE_BOM) {
        return utf16(rest, u16::from_le_bytes);
    }
    if let Some(rest) = bytes.strip_prefix(&UTF16_BE_BOM) {
        return utf16(rest, u16::from_be_bytes);
    }
    Cow::Borrowed(bytes)
}

/// A name's bytes as text; see the module doc.
pub fn name(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_owned(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
        let mut out = if big_endian { UTF16_BE_BOM.to_vec() } else { UTF16_LE_BOM.to_vec() };
        for u in text.encode_utf16() {
            out.extend(if big_endian { u.to_be_bytes() } else { u.to_le_bytes() });
        }
        out
    }

    #[test]
    fn byte_order_marks_are_read() {
        let text = "v 1 2 3\r\nnewmtl Matériau ✓\n";
        assert_eq!(&*decode(text.as_bytes()), text.as_bytes(), "no mark: the bytes as they are");
        assert_eq!(&*decode(&[&UTF8_BOM[..], text.as_bytes()].concat()), text.as_bytes());
        assert_eq!(&*decode(&utf16(text, false)), text.as_bytes(), "UTF-16 LE");
        assert_eq!(&*decode(&utf16(text, true)), text.as_bytes(), "UTF-16 BE");
        let mut odd = utf16("v", false);
        odd.push(0x41);
        assert_eq!(String::from_utf8(decode(&odd).into_owned()).unwrap(), "v\u{FFFD}");
        let lone_surrogate = [0xFF, 0xFE, 0x00, 0xD8, 0x41, 0x00];
        assert_eq!(String::from_utf8(decode(&lone_surrogate).into_owned()).unwrap(), "\u{FFFD}A");
    }

    #[test]
    fn names_are_utf8_or_latin1_and_stay_distinct() {
        assert_eq!(name("Matériau".as_bytes()), "Matériau");
        assert_eq!(name(b"Mat\xE9riau"), "Matériau", "Latin-1 é");
        assert_ne!(name(b"Mat\xE9"), name(b"Mat\xE8"));
        assert_eq!(name(b""), "");
    }
}
