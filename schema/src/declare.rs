//! The machinery behind [`crate::columns`]: one macro that turns the declaration of every setting and
//! measure into the typed settings, the axes, the row struct and the column metadata.

/// The first expression if given, else the second.
macro_rules! or_default {
    (; $default:expr) => {
        $default
    };
    ($given:expr; $default:expr) => {
        $given
    };
}
pub(crate) use or_default;

/// Declares the row: identity columns, settings (axes) and measures, in row order.
///
/// A setting reads `key: Type = default [, range(LO, HI)] [, applies PREDICATE else VALUE] [, added N]
/// [, id CELL] [, unit "u"];`: `applies` names a `fn(&Settings) -> bool` that says whether the setting applies to a
/// configuration (where it does not, normalization sets it to VALUE, so it never multiplies runs);
/// `added N` marks settings added in row format N (after the first), which join the configuration id only when
/// they differ from their default and their not-applicable value, so that existing configurations keep their ids;
/// `id` names a `fn(&Type) -> Cell` giving the cell the id hashes in place of the row cell (a setting that replaced
/// one recorded under another spelling hashes the old spelling, so configurations keep their ids).
/// A measure reads `key: Type, Role [= default] [, unit "u"] [, decimals N] [, added N];` (`added`: rows recorded
/// before format N lack the column and read as its default).
macro_rules! declare_columns {
    (
        identity {
            $( $(#[doc = $idoc:literal])+ $i:ident : $ity:ty ; )+
        }
        settings {
            $( $(#[doc = $sdoc:literal])+
               $s:ident : $sty:ty = $sdef:expr
               $(, range($lo:expr, $hi:expr))?
               $(, applies $pred:ident else $na:expr)?
               $(, added $added:literal)?
               $(, id $idf:ident)?
               $(, unit $sunit:literal)? ; )+
        }
        measures {
            $( $(#[doc = $mdoc:literal])+
               $m:ident : $mty:ty, $role:ident
               $(= $mdef:expr)?
               $(, unit $munit:literal)?
               $(, decimals $dec:literal)?
               $(, added $madded:literal)? ; )+
        }
    ) => {
        /// Every setting of one configuration, typed (see the declaration for each one's meaning).
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        pub struct Settings {
            $( $(#[doc = $sdoc])+ #[serde(with = "crate::value::as_text")] pub $s: $sty, )+
        }

        impl Default for Settings {
            fn default() -> Self {
                Settings { $( $s: $sdef, )+ }
            }
        }

        /// A setting: a config key, a row column and an axis of the sweep.
        #[allow(non_camel_case_types)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Axis {
            $( $(#[doc = $sdoc])+ $s, )+
        }

        /// A value of one axis.
        #[allow(non_camel_case_types)]
        #[derive(Clone, Debug, PartialEq)]
        pub enum AxisValue {
            $( $(#[doc = $sdoc])+ $s($sty), )+
        }

        impl Axis {
            /// Every axis, in row order.
            pub const ALL: &'static [Axis] = &[ $( Axis::$s, )+ ];

            /// The config key and row column.
            pub fn key(self) -> &'static str {
                match self { $( Axis::$s => stringify!($s), )+ }
            }

            /// The axis with config key `key`.
            pub fn from_key(key: &str) -> Option<Axis> {
                Axis::ALL.iter().copied().find(|a| a.key() == key)
            }

            /// The allowed integer or number range, if the declaration gives one.
            pub fn range(self) -> Option<(f64, f64)> {
                match self { $( Axis::$s => crate::declare::or_default!($( Some((($lo) as f64, ($hi) as f64)) )?; None), )+ }
            }

            /// What a config may give, in words, for error messages.
            pub fn allowed(self) -> String {
                use crate::value::AxisType;
                let range = match self.range() {
                    Some((lo, hi)) if self.is_integer() => format!("{}..={}", lo as i64, hi as i64),
                    // Float settings are f32: their bounds print as the f32 they were declared as.
                    Some((lo, hi)) => format!("{}..={}", lo as f32, hi as f32),
                    None => String::new(),
                };
                let text = match self { $( Axis::$s => <$sty>::allowed(&range), )+ };
                text.trim_end().to_string()
            }

            /// True for integer settings.
            pub fn is_integer(self) -> bool {
                use crate::value::AxisType;
                match self { $( Axis::$s => <$sty>::KIND == crate::row::Kind::Int, )+ }
            }

            /// The value written where the setting does not apply (`None` when it always applies).
            pub fn not_applicable(self) -> Option<AxisValue> {
                match self { $( Axis::$s => crate::declare::or_default!($( Some(AxisValue::$s($na)) )?; None), )+ }
            }

            /// The value a sweep uses when it does not name this axis.
            pub fn default_value(self) -> AxisValue {
                Settings::default().get(self)
            }

            /// Every value of the axis, for axes of names (`None` for numbers).
            pub fn choices(self) -> Option<Vec<AxisValue>> {
                use crate::value::AxisType;
                match self { $( Axis::$s => <$sty>::choices().map(|all| all.into_iter().map(AxisValue::$s).collect()), )+ }
            }

            /// The one-line meaning of the setting.
            pub fn doc(self) -> &'static str {
                match self { $( Axis::$s => concat!($($sdoc),+), )+ }
            }

            /// Its unit (empty for names and counts).
            pub fn unit(self) -> &'static str {
                match self { $( Axis::$s => crate::declare::or_default!($( $sunit )?; ""), )+ }
            }

            /// True for settings added after the first row format (see the configuration id).
            pub fn added(self) -> bool {
                match self { $( Axis::$s => crate::declare::or_default!($( $added > 1 )?; false), )+ }
            }

            /// True when the setting applies to every configuration.
            pub fn always_applies(self) -> bool {
                match self { $( Axis::$s => crate::declare::or_default!($( { let _: fn(&Settings) -> bool = $pred; false } )?; true), )+ }
            }

            /// Parses one config value for this axis; the error says what is allowed.
            pub fn parse(self, raw: crate::value::Raw<'_>) -> Result<AxisValue, String> {
                use crate::value::AxisType;
                let bad = |what: String| format!("{what} (allowed: {})", self.allowed());
                match self {
                    $( Axis::$s => {
                        let v = <$sty>::parse(raw).map_err(bad)?;
                        if let (Some((lo, hi)), Some(x)) = (self.range(), v.number()) {
                            if !(lo..=hi).contains(&x) {
                                return Err(bad(format!("{} is out of range", v.cell())));
                            }
                        }
                        Ok(AxisValue::$s(v))
                    } )+
                }
            }
        }

        impl AxisValue {
            /// The axis this value belongs to.
            pub fn axis(&self) -> Axis {
                match self { $( AxisValue::$s(_) => Axis::$s, )+ }
            }

            /// The value as a row cell.
            pub fn cell(&self) -> crate::row::Cell {
                use crate::value::AxisType;
                match self { $( AxisValue::$s(v) => v.cell(), )+ }
            }
        }

        impl std::fmt::Display for AxisValue {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                self.cell().fmt(f)
            }
        }

        impl Settings {
            /// The value of one axis.
            pub fn get(&self, axis: Axis) -> AxisValue {
                match axis { $( Axis::$s => AxisValue::$s(self.$s.clone()), )+ }
            }

            /// Sets one axis.
            pub fn set(&mut self, value: AxisValue) {
                match value { $( AxisValue::$s(v) => self.$s = v, )+ }
            }

            /// Whether `axis` applies to this configuration.
            pub fn applies(&self, axis: Axis) -> bool {
                match axis { $( Axis::$s => { true $( && $pred(self) )? } )+ }
            }

            /// The same settings with every setting that does not apply set to its not-applicable value.
            pub fn normalized(&self) -> Settings {
                let mut out = self.clone();
                $( $( if !$pred(self) { out.$s = $na; } )? )+
                out
            }

            /// The setting cells in row order.
            pub fn cells(&self) -> Vec<crate::row::Cell> {
                use crate::value::AxisType;
                vec![ $( self.$s.cell(), )+ ]
            }

            /// The cells that identify the configuration: every setting in row order (its `id` cell where the
            /// declaration names one), except `added` settings at their default or not-applicable value.
            pub fn id_cells(&self) -> Vec<crate::row::Cell> {
                use crate::value::AxisType;
                let default = Settings::default();
                let mut cells = Vec::new();
                $(
                    let cell = self.$s.cell();
                    let skip = Axis::$s.added()
                        && (cell == default.$s.cell() || cell == <$sty as AxisType>::not_applicable_cell());
                    if !skip {
                        cells.push(crate::declare::or_default!($( $idf(&self.$s) )?; cell));
                    }
                )+
                cells
            }
        }

        /// One recorded repetition: `runs.csv` holds one per line, columns in this order.
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(default)]
        pub struct Row {
            $( $(#[doc = $idoc])+ pub $i: $ity, )+
            $( $(#[doc = $sdoc])+ #[serde(with = "crate::value::as_text")] pub $s: $sty, )+
            $( $(#[doc = $mdoc])+ pub $m: $mty, )+
        }

        impl Default for Row {
            fn default() -> Self {
                Row {
                    $( $i: Default::default(), )+
                    $( $s: $sdef, )+
                    $( $m: crate::declare::or_default!($( $mdef )?; Default::default()), )+
                }
            }
        }

        impl Row {
            /// A row of `settings` with empty identity and measures.
            pub fn of(settings: &Settings) -> Row {
                Row { $( $s: settings.$s.clone(), )+ ..Row::default() }
            }

            /// The row's settings.
            pub fn settings(&self) -> Settings {
                Settings { $( $s: self.$s.clone(), )+ }
            }

            /// Replaces the row's settings.
            pub fn set_settings(&mut self, settings: &Settings) {
                $( self.$s = settings.$s.clone(); )+
            }

            /// Rounds every measure with declared decimals (so rows stay short and counters compare exactly).
            pub fn rounded(mut self) -> Row {
                $( $( self.$m = crate::row::Round::round_to(self.$m, $dec); )? )+
                self
            }

            /// The cell of `column`, if the row has that column.
            pub fn cell(&self, column: &str) -> Option<crate::row::Cell> {
                use crate::row::MeasureType;
                use crate::value::AxisType;
                Some(match column {
                    $( stringify!($i) => <$ity as MeasureType>::cell(&self.$i), )+
                    $( stringify!($s) => <$sty as AxisType>::cell(&self.$s), )+
                    $( stringify!($m) => <$mty as MeasureType>::cell(&self.$m), )+
                    _ => return None,
                })
            }
        }

        /// Every column of a row, in order.
        pub static COLUMNS: &[crate::row::Column] = &[
            $( crate::row::Column {
                name: stringify!($i),
                kind: <$ity as crate::row::MeasureType>::KIND,
                role: crate::row::Role::Identity,
                unit: "",
                added: 1,
                doc: concat!($($idoc),+),
            }, )+
            $( crate::row::Column {
                name: stringify!($s),
                kind: <$sty as crate::value::AxisType>::KIND,
                role: crate::row::Role::Setting,
                unit: crate::declare::or_default!($( $sunit )?; ""),
                added: crate::declare::or_default!($( $added )?; 1),
                doc: concat!($($sdoc),+),
            }, )+
            $( crate::row::Column {
                name: stringify!($m),
                kind: <$mty as crate::row::MeasureType>::KIND,
                role: crate::row::Role::$role,
                unit: crate::declare::or_default!($( $munit )?; ""),
                added: crate::declare::or_default!($( $madded )?; 1),
                doc: concat!($($mdoc),+),
            }, )+
        ];

        /// Every column's name as a constant: code reads a row's columns through these, never through literals.
        #[allow(non_upper_case_globals)]
        pub mod column {
            $( #[doc = concat!("The `", stringify!($i), "` column.")] pub const $i: &str = stringify!($i); )+
            $( #[doc = concat!("The `", stringify!($s), "` column.")] pub const $s: &str = stringify!($s); )+
            $( #[doc = concat!("The `", stringify!($m), "` column.")] pub const $m: &str = stringify!($m); )+
        }
    };
}
