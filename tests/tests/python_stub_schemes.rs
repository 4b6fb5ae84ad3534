//! The Python package's type stubs name the schemes of the registry: `_SchemeName` in
//! `python/preint/_native.pyi` is `Literal[…]` of every [`preint::SchemeInfo::name`] in the
//! registry's order, and the docstring of `SCHEMES` lists the same names (the runtime
//! `preint.SCHEMES` is built from the registry itself). A scheme added to the registry fails
//! this test until the stub names it.

use preint::Scheme;

fn stub() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../python/preint/_native.pyi");
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The quoted names in the first `[...]` after `prefix` in `text`.
fn quoted_list_after(text: &str, prefix: &str) -> Vec<String> {
    let at = text
        .find(prefix)
        .unwrap_or_else(|| panic!("`{prefix}` not found in the stub"));
    let rest = &text[at + prefix.len()..];
    let open = rest.find('[').expect("a list");
    let close = rest[open..].find(']').expect("the list's end") + open;
    rest[open + 1..close]
        .split(',')
        .map(|s| s.trim().trim_matches('"').to_string())
        .filter(|s| !s.is_empty())
        .collect()
}

fn registry_names() -> Vec<String> {
    Scheme::ALL
        .iter()
        .map(|s| s.info().name.to_string())
        .collect()
}

#[test]
fn the_stub_literal_lists_the_registry_schemes() {
    let text = stub();
    let literal = quoted_list_after(&text, "_SchemeName = Literal");
    assert_eq!(
        literal,
        registry_names(),
        "python/preint/_native.pyi: `_SchemeName = Literal[...]` must list the registry's \
         schemes in its order"
    );
    let doc = quoted_list_after(&text, "\"\"\"The scheme names: ");
    assert_eq!(
        doc,
        registry_names(),
        "the docstring of SCHEMES in the stub"
    );
}

#[test]
fn the_list_reader_reads_a_literal() {
    let text = "x = Literal[\"a\", \"b-c\"]\ny = 1";
    assert_eq!(quoted_list_after(text, "x = Literal"), ["a", "b-c"]);
}
