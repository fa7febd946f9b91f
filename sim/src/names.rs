//! Enums chosen by name on the command line, in Python and in files.
//!
//! Every setting with a fixed set of values (`--backend physics|grid`, `--profile`,
//! `--oracle`, `--loss`, ...) is a fieldless enum whose names are written once, in a
//! [`names!`](crate::names!) invocation: the list of names, the name of a value, printing it
//! and reading it back all come from that one table, so they cannot drift apart. Each crate
//! keeps its own error type and message for an unknown name.

/// Gives a fieldless enum its names: `ALL` and `NAMES` (in the order listed), `name()`,
/// `Display`, and `FromStr`, whose error for an unknown name is `$make` (built from the text,
/// bound to `$text`).
///
/// ```
/// #[derive(Clone, Copy, Debug, PartialEq)]
/// enum Colour { Red, Blue }
/// sim::names!(Colour { Red = "red", Blue = "blue" } unknown(text) -> String {
///     format!("unknown colour {text:?}: choose red or blue")
/// });
/// assert_eq!("blue".parse::<Colour>(), Ok(Colour::Blue));
/// assert_eq!(Colour::Red.to_string(), "red");
/// assert_eq!(Colour::NAMES, ["red", "blue"]);
/// assert!("green".parse::<Colour>().unwrap_err().contains("green"));
/// ```
///
/// A value renamed keeps its old name as an alias, read but never written or listed:
///
/// ```
/// #[derive(Clone, Copy, Debug, PartialEq)]
/// enum Colour { Crimson, Blue }
/// sim::names!(Colour { Crimson = "crimson", Blue = "blue" } aliases { "red" => Crimson }
///     unknown(text) -> String { format!("unknown colour {text:?}") });
/// assert_eq!("red".parse::<Colour>(), Ok(Colour::Crimson));
/// assert_eq!(Colour::Crimson.to_string(), "crimson");
/// assert_eq!(Colour::NAMES, ["crimson", "blue"]);
/// ```
#[macro_export]
macro_rules! names {
    ($ty:ident { $($variant:ident = $name:literal),+ $(,)? } unknown($text:ident) -> $err:ty { $make:expr }) => {
        $crate::names!($ty { $($variant = $name),+ } aliases {} unknown($text) -> $err { $make });
    };
    ($ty:ident { $($variant:ident = $name:literal),+ $(,)? } aliases { $($alias:literal => $aliased:ident),* $(,)? } unknown($text:ident) -> $err:ty { $make:expr }) => {
        impl $ty {
            /// Every value, in the order of `NAMES`.
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];

            /// The names the values are chosen by.
            pub const NAMES: [&'static str; [$($name),+].len()] = [$($name),+];

            /// This value's name.
            pub const fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)+
                }
            }
        }

        impl ::core::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::core::str::FromStr for $ty {
            type Err = $err;

            fn from_str($text: &str) -> ::core::result::Result<$ty, $err> {
                match $text {
                    $($name => Ok($ty::$variant),)+
                    $($alias => Ok($ty::$aliased),)*
                    _ => Err($make),
                }
            }
        }
    };
}
