//! Tables for C builds: [`c_header`] writes a table file as a C header holding its bytes,
//! so that C firmware can embed a table at build time and decode it with the C API
//! (`include/mlmap.h`), as `build.rs` embeds one for Rust.
//!
//! The header declares the array (`extern const uint8_t NAME[NAME_LEN]`) wherever it is
//! included; the one translation unit that defines `NAME_IMPLEMENTATION` (upper case)
//! before including it also defines the array, so the program holds one copy. It
//! compiles as C99 and later and as C++11 and later, warning-free under `-pedantic
//! -Wall -Wextra`. Class names appear only in its opening comment, escaped by
//! [`c_comment`].

use std::fmt::{self, Write as _};

use crate::escape::c_comment;
use crate::DynTable;
use mlmap_core::lent;
use mlmap_core::DecodeError;

/// Why a table could not be exported.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum ExportError {
    /// The bytes are not a valid table.
    Table(DecodeError),
    /// The name cannot name the array (see [`check_c_name`]).
    Name {
        /// The name given.
        name: String,
        /// Why it cannot.
        error: CNameError,
    },
}

impl fmt::Display for ExportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Table(e) => write!(f, "not a valid table: {e}"),
            Self::Name { name, error } => write!(f, "{name:?} cannot name the array: {error}"),
        }
    }
}

impl std::error::Error for ExportError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Table(e) => Some(e),
            Self::Name { error, .. } => Some(error),
        }
    }
}

/// Why a name cannot name the array of a C header (see [`check_c_name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum CNameError {
    /// Not an identifier of ASCII letters, digits and `_` starting with a letter or `_`.
    NotIdentifier,
    /// Longer than [`C_NAME_MAX`] characters.
    TooLong,
    /// A keyword of C (C99 to C23) or C++ (to C++23).
    Keyword,
    /// Reserved by the C or C++ standard: it starts with `_` (reserved at file scope
    /// in C; `__` and `_` followed by an upper-case letter everywhere), holds `__`
    /// (reserved in C++), or is `main`.
    Reserved,
    /// A name `<stdint.h>` reserves (which the header includes): ending in `_t`
    /// (also reserved by POSIX for types), or a macro name beginning with `INT` or
    /// `UINT` and ending in `_MAX`, `_MIN`, `_WIDTH` or `_C`, or another limit of that
    /// header.
    Library,
}

impl fmt::Display for CNameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NotIdentifier => {
                "not a C identifier (ASCII letters, digits and `_`, not starting with a digit)"
            }
            Self::TooLong => "longer than 63 characters",
            Self::Keyword => "a C or C++ keyword",
            Self::Reserved => {
                "reserved by the C or C++ standard (a leading `_`, `__` anywhere, or `main`)"
            }
            Self::Library => "a name reserved by <stdint.h> (`*_t`, INT*_MAX and the like)",
        })
    }
}

impl std::error::Error for CNameError {}

/// Longest array name of [`c_header`], in characters: the significant length C99
/// guarantees for internal identifiers and macro names.
pub const C_NAME_MAX: usize = 63;

/// The keywords of C99, C11, C23 and C++ (to C++23), and the alternative tokens of
/// C++ (`and`, `or`, ...), sorted. (C11's `_Alignas` and the like start with `_` and an
/// upper-case letter: reserved anyway.)
const KEYWORDS: &[&str] = &[
    "alignas",
    "alignof",
    "and",
    "and_eq",
    "asm",
    "auto",
    "bitand",
    "bitor",
    "bool",
    "break",
    "case",
    "catch",
    "char",
    "char16_t",
    "char32_t",
    "char8_t",
    "class",
    "co_await",
    "co_return",
    "co_yield",
    "compl",
    "concept",
    "const",
    "const_cast",
    "consteval",
    "constexpr",
    "constinit",
    "continue",
    "decltype",
    "default",
    "delete",
    "do",
    "double",
    "dynamic_cast",
    "else",
    "enum",
    "explicit",
    "export",
    "extern",
    "false",
    "float",
    "for",
    "friend",
    "goto",
    "if",
    "inline",
    "int",
    "long",
    "mutable",
    "namespace",
    "new",
    "noexcept",
    "not",
    "not_eq",
    "nullptr",
    "operator",
    "or",
    "or_eq",
    "private",
    "protected",
    "public",
    "register",
    "reinterpret_cast",
    "requires",
    "restrict",
    "return",
    "short",
    "signed",
    "sizeof",
    "static",
    "static_assert",
    "static_cast",
    "struct",
    "switch",
    "template",
    "this",
    "thread_local",
    "throw",
    "true",
    "try",
    "typedef",
    "typeid",
    "typename",
    "typeof",
    "typeof_unqual",
    "union",
    "unsigned",
    "using",
    "virtual",
    "void",
    "volatile",
    "wchar_t",
    "while",
    "xor",
    "xor_eq",
];

/// Limits `<stdint.h>` defines besides the `INT*` and `UINT*` ones.
const STDINT_LIMITS: &[&str] = &[
    "PTRDIFF_MAX",
    "PTRDIFF_MIN",
    "PTRDIFF_WIDTH",
    "SIG_ATOMIC_MAX",
    "SIG_ATOMIC_MIN",
    "SIG_ATOMIC_WIDTH",
    "SIZE_MAX",
    "SIZE_WIDTH",
    "WCHAR_MAX",
    "WCHAR_MIN",
    "WCHAR_WIDTH",
    "WINT_MAX",
    "WINT_MIN",
    "WINT_WIDTH",
];

/// Checks that `name` can name the array of a [`c_header`] in C and C++: an identifier
/// of ASCII letters, digits and `_`, not starting with a digit, at most
/// [`C_NAME_MAX`] characters, not a keyword of C99, C11, C23 or C++, not reserved by
/// either standard (a leading `_`, `__` anywhere, `main`), and not a name the included
/// `<stdint.h>` reserves. (The names of the C library's functions and objects are
/// reserved too, for identifiers with external linkage such as the array; the linker
/// reports those.)
///
/// # Errors
///
/// The first rule broken, in that order.
///
/// # Examples
///
/// ```
/// use mlmap_host::export::{check_c_name, CNameError};
/// assert_eq!(check_c_name("calib_table"), Ok(()));
/// assert_eq!(check_c_name("int"), Err(CNameError::Keyword));
/// assert_eq!(check_c_name("_table"), Err(CNameError::Reserved));
/// assert_eq!(check_c_name("my-table"), Err(CNameError::NotIdentifier));
/// ```
pub fn check_c_name(name: &str) -> Result<(), CNameError> {
    let ident = name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
        && name.bytes().next().is_some_and(|b| !b.is_ascii_digit());
    if !ident {
        return Err(CNameError::NotIdentifier);
    }
    if name.len() > C_NAME_MAX {
        return Err(CNameError::TooLong);
    }
    if KEYWORDS.binary_search(&name).is_ok() {
        return Err(CNameError::Keyword);
    }
    if name.starts_with('_') || name.contains("__") || name == "main" {
        return Err(CNameError::Reserved);
    }
    let int_macro = (name.starts_with("INT") || name.starts_with("UINT"))
        && ["_MAX", "_MIN", "_WIDTH", "_C"]
            .iter()
            .any(|s| name.ends_with(s));
    if name.ends_with("_t") || int_macro || STDINT_LIMITS.contains(&name) {
        return Err(CNameError::Library);
    }
    Ok(())
}

/// Alignment of the byte array in the header.
pub const C_ARRAY_ALIGN: usize = 8;

/// A C header embedding the table `bytes` (a `.mlmap` file, checked to be a valid table
/// first) as the array `const uint8_t NAME[NAME_LEN]`, aligned to [`C_ARRAY_ALIGN`]
/// bytes, with the length as the macro `NAME_LEN` (upper case) and, in a comment, the
/// length, the CRC-32, the shape and the class names (escaped by
/// [`c_comment`]). `source` names the file the bytes came
/// from, in that comment.
///
/// The header declares the array; the translation unit that defines
/// `NAME_IMPLEMENTATION` before including it defines it (one in the program).
///
/// # Examples
///
/// ```
/// let bytes = include_bytes!("../../tables/default.mlmap");
/// let h = mlmap_host::export::c_header(bytes, "calib_table", "default.mlmap")?;
/// assert!(h.contains("#define CALIB_TABLE_LEN 1704u"));
/// assert!(h.contains("extern const uint8_t calib_table[CALIB_TABLE_LEN];"));
/// assert!(h.contains("#if defined(CALIB_TABLE_IMPLEMENTATION)"));
/// # Ok::<(), mlmap_host::export::ExportError>(())
/// ```
///
/// # Errors
///
/// [`ExportError::Name`] for a name [`check_c_name`] refuses, [`ExportError::Table`]
/// when the bytes do not decode.
pub fn c_header(bytes: &[u8], name: &str, source: &str) -> Result<String, ExportError> {
    check_c_name(name).map_err(|error| ExportError::Name {
        name: name.to_owned(),
        error,
    })?;
    let table = DynTable::from_bytes(bytes).map_err(ExportError::Table)?;
    let upper = name.to_ascii_uppercase();
    let len = bytes.len();
    // The last four bytes are the CRC-32 of the others, little-endian (docs/FORMAT.md).
    let crc = bytes
        .len()
        .checked_sub(4)
        .and_then(|n| bytes.get(n..))
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(0, u32::from_le_bytes);
    let names: Vec<String> = table.class_names().map(c_comment).collect();
    let bayes = match table.bayes_head() {
        Some(b) => format!(
            "Bayes head: {} bins per logit, {} categories",
            b.bins(),
            b.categories()
        ),
        None => "no Bayes head".to_owned(),
    };
    let bayes = match table.open_params() {
        Some(o) => format!(
            "{bayes},\n * open head: temperature {}, epsilon {:e}",
            o.temperature(),
            o.epsilon()
        ),
        None => bayes,
    };
    let source = c_comment(source);
    let (arena_a, arena_b) = lent::StorageShape::of(bytes, |_| Ok(()))
        .ok()
        .and_then(|s| lent::ArenaLayout::size_terms(&s))
        .ok_or(ExportError::Table(mlmap_core::DecodeError::Malformed))?;
    let mut h = String::with_capacity(len * 6 + 2048);
    let guard = format!("{upper}_H");
    let imp = format!("{upper}_IMPLEMENTATION");
    // Writing to a String cannot fail.
    let _ = write!(
        h,
        "/* Generated by `mlmap export-c` from {source}; do not edit.\n\
         \x20*\n\
         \x20* An mlmap table: K = {k} classes ({classes}); ML head {bins_ml} bins, MAP head\n\
         \x20* {bins_map} bins, {bayes}.\n\
         \x20* Length: {len} bytes. CRC-32 (ISO-HDLC, the last 4 bytes, little-endian): 0x{crc:08x}.\n\
         \x20* Class names are escaped: \\xHH, \\uXXXX and \\UXXXXXXXX stand for the characters\n\
         \x20* with those codes, among them every `*`, `/`, `?` and backslash.\n\
         \x20*\n\
         \x20* This header declares the array {name}. Exactly one file of the program\n\
         \x20* defines it, by defining {imp} before including the header:\n\
         \x20*\n\
         \x20*   #define {imp}\n\
         \x20*   #include \"this header\"\n\
         \x20*\n\
         \x20* Every other file includes it plainly. Decode the table once with the C API\n\
         \x20* (mlmap.h):\n\
         \x20*   mlmap_table_decode(&table, sizeof table, {name}, {upper}_LEN);\n\
         \x20*\n\
         \x20* C99 or later, or C++11 or later.\n\
         \x20*/\n\
         #ifndef {guard}\n\
         #define {guard}\n\
         \n\
         #include <stddef.h>\n\
         #include <stdint.h>\n\
         \n\
         /** Length of {name} in bytes. */\n\
         #define {upper}_LEN {len}u\n\
         \n\
         /** Bytes of arena mlmap_table_init() needs for this table, exactly, on a target\n\
          * with 4- or 8-byte pointers (arena layout {layout}). */\n\
         #define {upper}_ARENA_SIZE ((size_t){arena_a} + (size_t){arena_b} * sizeof(void *))\n\
         /** The arena layout {upper}_ARENA_SIZE is for. */\n\
         #define {upper}_ARENA_LAYOUT {layout}\n\
         /* A header of another arena layout than this size's fails the build (include\n\
          * mlmap.h first for the check). */\n\
         #if defined(MLMAP_ARENA_LAYOUT) && MLMAP_ARENA_LAYOUT != {upper}_ARENA_LAYOUT\n\
         #error \"{name}: written by mlmap export-c for another arena layout than mlmap.h's\"\n\
         #endif\n\
         /* The size holds for 4- and 8-byte pointers only. */\n\
         typedef char {name}_arena_pointer_check[(sizeof(void *) == 4 || sizeof(void *) == 8) ? 1 : -1];\n\
         \n\
         #ifdef __cplusplus\n\
         extern \"C\" {{\n\
         #endif\n\
         \n\
         /** The table file's bytes, aligned to {align} bytes. */\n\
         extern const uint8_t {name}[{upper}_LEN];\n\
         \n\
         #ifdef __cplusplus\n\
         }}\n\
         #endif\n\
         \n\
         #endif /* {guard} */\n\
         \n\
         #if defined({imp}) && !defined({upper}_DEFINED)\n\
         #define {upper}_DEFINED\n\
         \n\
         /* The alignment: C++11 alignas, C11 _Alignas, else the compiler's own. */\n\
         #if defined(__cplusplus) && __cplusplus >= 201103L\n\
         #define {upper}_ALIGNED alignas({align})\n\
         #elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L\n\
         #define {upper}_ALIGNED _Alignas({align})\n\
         #elif defined(__GNUC__)\n\
         #define {upper}_ALIGNED __attribute__((aligned({align})))\n\
         #elif defined(_MSC_VER)\n\
         #define {upper}_ALIGNED __declspec(align({align}))\n\
         #else\n\
         #define {upper}_ALIGNED /* no alignment: mlmap_table_decode reads any address */\n\
         #endif\n\
         \n\
         {upper}_ALIGNED const uint8_t {name}[{upper}_LEN] = {{\n",
        k = names.len(),
        classes = names.join(", "),
        bins_ml = table.bins_ml(),
        bins_map = table.bins_map(),
        align = C_ARRAY_ALIGN,
        layout = lent::ARENA_LAYOUT,
    );
    for row in bytes.chunks(12) {
        h.push_str("   ");
        for b in row {
            let _ = write!(h, " 0x{b:02x},");
        }
        h.push('\n');
    }
    let _ = write!(h, "}};\n\n#endif /* {imp} */\n");
    Ok(h)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHIPPED: &[u8] = include_bytes!("../../tables/default.mlmap");

    /// The bytes between the braces of the array, parsed back.
    fn array_bytes(h: &str) -> Vec<u8> {
        let start = h.find("= {").unwrap() + 3;
        let end = h[start..].find("};").unwrap() + start;
        h[start..end]
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| u8::from_str_radix(s.trim_start_matches("0x"), 16).unwrap())
            .collect()
    }

    #[test]
    fn header_holds_the_arena_size_for_both_pointer_sizes() {
        let h = c_header(SHIPPED, "calib_table", "default.mlmap").unwrap();
        let shape = lent::StorageShape::of(SHIPPED, |_| Ok(())).unwrap();
        let (a, b) = lent::ArenaLayout::size_terms(&shape).unwrap();
        for p in [4, 8] {
            assert_eq!(a + b * p, lent::ArenaLayout::new(&shape, p).unwrap().size);
        }
        assert!(h.contains(&format!(
            "#define CALIB_TABLE_ARENA_SIZE ((size_t){a} + (size_t){b} * sizeof(void *))\n"
        )));
        assert!(h.contains("#define CALIB_TABLE_ARENA_LAYOUT 1\n"));
        // A 3-class table with a Bayes head: well under 4 KB on a 32-bit target.
        assert!(a + 4 * b <= 4096, "{}", a + 4 * b);
    }

    #[test]
    fn header_holds_the_bytes_length_and_crc() {
        let h = c_header(SHIPPED, "calib_table", "tables/default.mlmap").unwrap();
        assert_eq!(array_bytes(&h), SHIPPED);
        assert!(h.contains(&format!("#define CALIB_TABLE_LEN {}u\n", SHIPPED.len())));
        assert!(h.contains("\nextern const uint8_t calib_table[CALIB_TABLE_LEN];\n"));
        assert!(
            h.contains("\nCALIB_TABLE_ALIGNED const uint8_t calib_table[CALIB_TABLE_LEN] = {\n")
        );
        assert!(h.contains(
            "#if defined(CALIB_TABLE_IMPLEMENTATION) && !defined(CALIB_TABLE_DEFINED)\n"
        ));
        assert!(h.contains("#define CALIB_TABLE_ALIGNED _Alignas(8)\n"));
        assert!(h.contains("#define CALIB_TABLE_ALIGNED alignas(8)\n"));
        assert!(h.contains("#define CALIB_TABLE_ALIGNED __attribute__((aligned(8)))\n"));
        assert!(!h.contains("static"));
        // The CRC of the comment, computed here independently of the table's own field.
        let crc =
            crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&SHIPPED[..SHIPPED.len() - 4]);
        assert!(
            h.contains(&format!(
                "CRC-32 (ISO-HDLC, the last 4 bytes, little-endian): 0x{crc:08x}."
            )),
            "{h}"
        );
        assert!(h.contains("K = 3 classes (car, cyclist, pedestrian); ML head 22 bins, MAP head"));
        assert!(h.contains("17 bins, Bayes head: 22 bins per logit, 4 categories,\n"));
        assert!(h.contains(" * open head: temperature 1, epsilon 0e0.\n"));
        assert!(h.contains("from tables\\x2fdefault.mlmap;"));
        assert!(h.starts_with("/* Generated by `mlmap export-c`"));
        assert!(h.ends_with("#endif /* CALIB_TABLE_IMPLEMENTATION */\n"));
    }

    #[test]
    fn a_table_without_bayes_head() {
        let small = include_bytes!("../../tests/golden/layer/small.mlmap");
        let h = c_header(small, "t", "small.mlmap").unwrap();
        assert_eq!(array_bytes(&h), small);
        assert!(h.contains("no Bayes head."));
    }

    #[test]
    fn refuses_bad_tables_and_names() {
        let mut bad = SHIPPED.to_vec();
        bad[100] ^= 1;
        assert_eq!(
            c_header(&bad, "t", "x"),
            Err(ExportError::Table(DecodeError::Corrupted))
        );
        assert_eq!(
            c_header(b"MLM", "t", "x"),
            Err(ExportError::Table(DecodeError::Truncated))
        );
        let long = "t".repeat(C_NAME_MAX + 1);
        for (name, error) in [
            ("", CNameError::NotIdentifier),
            ("1table", CNameError::NotIdentifier),
            ("my-table", CNameError::NotIdentifier),
            ("tåble", CNameError::NotIdentifier),
            ("a b", CNameError::NotIdentifier),
            ("t\n", CNameError::NotIdentifier),
            (long.as_str(), CNameError::TooLong),
            ("int", CNameError::Keyword),
            ("while", CNameError::Keyword),
            ("restrict", CNameError::Keyword),
            ("bool", CNameError::Keyword),
            ("constexpr", CNameError::Keyword),
            ("typeof", CNameError::Keyword),
            ("class", CNameError::Keyword),
            ("xor_eq", CNameError::Keyword),
            ("char8_t", CNameError::Keyword),
            ("_x", CNameError::Reserved),
            ("_X", CNameError::Reserved),
            ("__x", CNameError::Reserved),
            ("_Alignas", CNameError::Reserved),
            ("a__b", CNameError::Reserved),
            ("main", CNameError::Reserved),
            ("uint8_t", CNameError::Library),
            ("table_t", CNameError::Library),
            ("INT8_MAX", CNameError::Library),
            ("UINT64_C", CNameError::Library),
            ("INTPTR_WIDTH", CNameError::Library),
            ("SIZE_MAX", CNameError::Library),
        ] {
            assert_eq!(
                c_header(SHIPPED, name, "x"),
                Err(ExportError::Name {
                    name: name.to_owned(),
                    error
                }),
                "{name:?}"
            );
        }
        for name in [
            "t",
            "T",
            "x1",
            "calib_table",
            "int_table",
            "Main",
            "a_b_c",
            &long[1..],
        ] {
            assert_eq!(check_c_name(name), Ok(()), "{name:?}");
        }
        assert!(KEYWORDS.windows(2).all(|w| w[0] < w[1]), "sorted");
        // A comment terminator in the file name cannot end the comment early.
        let h = c_header(SHIPPED, "t", "evil*/name\n").unwrap();
        assert!(h.contains("from evil\\x2a\\x2fname\\x0a;"));
    }
}
