//! The goodness of fit as every command prints it ([`preint_calib::fit`]; its JSON is
//! [`preint_analysis::consistency::fit_json`]): [`fit_text`] (a `fit:` line, and a `warning:`
//! line when not credible) and [`strict`] (`--strict`: a fit that is not credible is a refusal,
//! exit 2).

use crate::{CliError, Output};
use preint_calib::Fit;

/// `fit of the {what}: credible ({why})`, or, when not credible, `warning: the {what} fit is
/// not credible: {why}` (with its likely cause); one line, ending with a newline.
pub fn fit_text(f: &Fit, what: &str) -> String {
    if f.credible {
        format!("fit of the {what}: credible ({})\n", f.why)
    } else {
        format!("warning: the {what} fit is not credible: {}\n", f.why)
    }
}

/// `--strict`: `output` as it is, or, when `strict` and the fit is not credible, a refusal
/// that prints it and then why (exit 2).
pub fn strict(strict: bool, output: Output, f: &Fit, what: &str) -> Result<Output, CliError> {
    if strict && !f.credible {
        return Err(CliError::Refused {
            output: Box::new(output),
            msg: format!("the {what} fit is not credible (--strict): {}", f.why),
        });
    }
    Ok(output)
}
