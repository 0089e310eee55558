//! JSON Schema refinements for the derived schemas of parameter structs
//! (`#[schemars(transform = ...)]`): the rules their `validate()` applies
//! that JSON Schema can state but the derive attributes cannot (exclusive
//! bounds on the items of a vector, a vector that must not be zero). The
//! scalar bounds use the derive's own `range` and `extend` attributes.
//!
//! Each refinement states the rule exactly or more loosely than
//! `validate()` does, never more strictly: a schema must not refuse a
//! value the reader accepts.

use schemars::Schema;

/// A vector `[x, y, z]` that is not exactly `[0, 0, 0]` (a direction: it
/// is normalized). `validate()` also refuses vectors shorter than a
/// tolerance; the schema refuses only the zero vector itself. On an
/// optional vector the rule leaves `null` allowed.
pub fn non_zero_vector(schema: &mut Schema) {
    schema.insert(
        "not".into(),
        schemars::json_schema!({"const": [0, 0, 0]}).into(),
    );
}

/// Every item of the vector `> 0` (`exclusiveMinimum: 0` on its items).
pub fn positive_items(schema: &mut Schema) {
    if let Some(items) = schema.get_mut("items").and_then(|v| v.as_object_mut()) {
        items.insert("exclusiveMinimum".into(), 0.into());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refinements_add_their_keywords() {
        let mut v = schemars::json_schema!({"type": "array", "items": {"type": "number"}});
        non_zero_vector(&mut v);
        positive_items(&mut v);
        assert_eq!(
            v.as_value(),
            &schemars::json_schema!({
                "type": "array",
                "items": {"type": "number", "exclusiveMinimum": 0},
                "not": {"const": [0, 0, 0]}
            })
            .to_value()
        );
    }
}
