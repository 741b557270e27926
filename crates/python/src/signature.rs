//! The Python signatures of the extension's classes and functions as the type stubs declare
//! them: each class module declares its own (`STUB`) next to its `#[pymethods]`, and the stub
//! generator (`stubs.rs`) reads them all. A leaf: it imports none of the modules that use it.

/// One member of a class as the stubs declare it; the docstring is the extension's.
pub enum Member {
    /// A read-only property and its Python type: `name: Final[type]`.
    Property(&'static str, &'static str),
    /// A method: its name and its signature after the name, `(self, t: float) -> int`.
    Method(&'static str, &'static str),
    /// A static method: name and signature.
    Static(&'static str, &'static str),
    /// A method taking a key path (`key: str`) that returns the value there: an overload per
    /// section of a study file (`Literal["materials"]` gives `List[MaterialsTable]`), then its
    /// signature for any key path.
    BySection(&'static str, &'static str),
    /// An instance attribute of an exception, set on each raised instance: `name: type`.
    Attribute(&'static str, &'static str),
}

/// A class of the extension as the stubs declare it.
pub struct Class {
    pub name: &'static str,
    /// Its bases as written in the stubs (`FlexmbsError, KeyError`); empty: none.
    pub bases: &'static str,
    pub members: &'static [Member],
}

/// A function of the module: name and signature.
pub(crate) struct Function(pub &'static str, pub &'static str);
