//! Typed Python exceptions carrying the Rust error's message.
//!
//! The classes are defined in `preint/_errors.py` (each derives from `preint.Error` and from the
//! built-in class a Python user would catch, e.g. `ValueError`); here a Rust error becomes an
//! instance of one of them with the Rust `Display` text as its message and the variant's name
//! as its `kind` attribute.

use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception classes of `preint/_errors.py`.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Class {
    Preint,
    Merge,
    Factor,
    Shape,
    Input,
    Calibration,
}

impl Class {
    fn name(self) -> &'static str {
        match self {
            Class::Preint => "PreintError",
            Class::Merge => "MergeError",
            Class::Factor => "FactorError",
            Class::Shape => "ShapeError",
            Class::Input => "InputError",
            Class::Calibration => "CalibrationError",
        }
    }
}

/// The variant name of a Rust error: the first identifier of its `Debug` text.
pub(crate) fn variant_name<E: std::fmt::Debug>(e: &E) -> String {
    let d = format!("{e:?}");
    d.split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .next()
        .unwrap_or("")
        .to_string()
}

/// An exception of class `class` with message `msg` and `kind`.
pub(crate) fn new_err(class: Class, kind: &str, msg: String) -> PyErr {
    Python::attach(|py| {
        let ty = match py
            .import("preint._errors")
            .and_then(|m| m.getattr(class.name()))
            .and_then(|t| Ok(t.cast_into::<PyType>()?))
        {
            Ok(t) => t,
            Err(e) => return e,
        };
        let err = PyErr::from_type(ty, msg);
        let _ = err.value(py).setattr("kind", kind);
        err
    })
}

/// A Rust error as an exception of class `class`.
pub(crate) fn raise<E: std::fmt::Display + std::fmt::Debug>(class: Class, e: E) -> PyErr {
    new_err(class, &variant_name(&e), e.to_string())
}

/// A [`preint::PreintError`] as `preint.PreintError`.
pub(crate) fn preint_err(e: preint::PreintError) -> PyErr {
    raise(Class::Preint, e)
}

/// A `preint.ShapeError` (kind `"Shape"`) with message `msg`.
pub(crate) fn shape_err(msg: impl Into<String>) -> PyErr {
    new_err(Class::Shape, "Shape", msg.into())
}
