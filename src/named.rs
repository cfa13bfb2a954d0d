//! Enums a user picks by name (a flag's value, a report's label): each value's name and doc
//! comment in one table, from which the binary builds its command-line parsers (the library
//! defines no command-line types) and `Display` and `FromStr` write and read the names.
//!
//! [`named_enum!`] declares such an enum: a variant is written `Variant = "name"` under its
//! doc comment, and the doc comment is also what `--help` says of the value.

/// One value of a [`Named`] enum: the value, its name and its doc comment.
#[derive(Clone, Copy, Debug)]
pub struct NamedValue<T: 'static> {
    /// The value.
    pub value: T,
    /// Its name on the command line.
    pub name: &'static str,
    /// The variant's attributes in order: `Some(line)` for each doc comment line, `None` for
    /// any other attribute (`#[default]`).
    pub doc: &'static [Option<&'static str>],
}

impl<T> NamedValue<T> {
    /// The first paragraph of the doc comment as one line, without its final period: the
    /// summary rustdoc shows, and the help `--help` gives the value.
    pub fn summary(&self) -> String {
        let lines = self.doc.iter().flatten().map(|line| line.trim());
        let paragraph: Vec<&str> = lines
            .skip_while(|line| line.is_empty())
            .take_while(|line| !line.is_empty())
            .collect();
        let mut summary = paragraph.join(" ");
        if summary.ends_with('.') && !summary.ends_with("..") {
            summary.pop();
        }
        summary
    }
}

/// An enum whose values have names ([`named_enum!`] implements it).
pub trait Named: Copy + PartialEq + Sized + 'static {
    /// Every value, in the order `--help` lists them.
    const VALUES: &'static [NamedValue<Self>];

    /// The value called `name` (exactly: names are lowercase).
    fn from_name(name: &str) -> Option<Self> {
        Self::VALUES
            .iter()
            .find(|v| v.name == name)
            .map(|v| v.value)
    }

    /// The names, in order, for an error that lists them.
    fn names() -> Vec<&'static str> {
        Self::VALUES.iter().map(|v| v.name).collect()
    }
}

/// The text of a doc attribute, `None` for any other (the variants' attributes pass through
/// [`named_enum!`] as `ident tokens`).
macro_rules! doc_line {
    (doc = $text:literal) => {
        Some($text)
    };
    ($($other:tt)*) => {
        None
    };
}

pub(crate) use doc_line;

/// Declares an enum with a name per variant (`Variant = "name"`), and implements [`Named`],
/// `Display` (the name) and `FromStr` (from the name) for it. The enum's attributes and each
/// variant's doc comment and attributes (`#[default]`) are kept as written.
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $Enum:ident {
            $(
                $(#[$attr:ident $($args:tt)*])*
                $Variant:ident = $name:literal,
            )+
        }
    ) => {
        $(#[$meta])*
        $vis enum $Enum {
            $(
                $(#[$attr $($args)*])*
                $Variant,
            )+
        }

        impl $crate::named::Named for $Enum {
            const VALUES: &'static [$crate::named::NamedValue<Self>] = &[$(
                $crate::named::NamedValue {
                    value: $Enum::$Variant,
                    name: $name,
                    doc: &[$($crate::named::doc_line!($attr $($args)*)),*],
                },
            )+];
        }

        impl $Enum {
            /// Its name, as `Display` writes it and `FromStr` reads it.
            pub fn name(self) -> &'static str {
                match self {
                    $($Enum::$Variant => $name,)+
                }
            }
        }

        impl std::fmt::Display for $Enum {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $Enum {
            type Err = String;

            fn from_str(name: &str) -> std::result::Result<Self, String> {
                <Self as $crate::named::Named>::from_name(name).ok_or_else(|| {
                    let names = <Self as $crate::named::Named>::names().join(", ");
                    format!("`{name}`: expected one of {names}")
                })
            }
        }
    };
}
pub(crate) use named_enum;

#[cfg(test)]
mod tests {
    use super::Named;

    super::named_enum! {
        /// A test enum.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub enum Fruit {
            /// A red one.
            #[default]
            Apple = "apple",
            /// A long one, described
            /// on two lines.
            ///
            /// A second paragraph.
            Banana = "banana-split",
            /// Ends in an ellipsis...
            Cherry = "cherry",
        }
    }

    #[test]
    fn names_read_and_write_both_ways() {
        for v in Fruit::VALUES {
            assert_eq!(v.value.name(), v.name);
            assert_eq!(v.value.to_string(), v.name);
            assert_eq!(v.name.parse::<Fruit>(), Ok(v.value));
        }
        assert_eq!(Fruit::default(), Fruit::Apple);
        assert_eq!(
            "Banana".parse::<Fruit>(),
            Err("`Banana`: expected one of apple, banana-split, cherry".to_string())
        );
    }

    #[test]
    fn the_summary_is_the_first_paragraph_on_one_line_without_its_period() {
        let summaries: Vec<String> = Fruit::VALUES.iter().map(|v| v.summary()).collect();
        assert_eq!(
            summaries,
            [
                "A red one",
                "A long one, described on two lines",
                "Ends in an ellipsis..."
            ]
        );
    }
}
