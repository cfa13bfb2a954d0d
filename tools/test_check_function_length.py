#!/usr/bin/env python3
"""Tests of tools/check_function_length.py: lengths counted from `fn` to the closing brace,
braces inside strings, comments and character literals not counted, unit-test modules and
bodiless trait methods left out.

  python3 tools/test_check_function_length.py
"""
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import check_function_length as check  # noqa: E402

SOURCE = '''
/// A doc comment with a brace {.
pub fn three() -> [f32; 3] {
    [1.0, 2.0, 3.0]
}

fn literals<'a>(s: &'a str) -> usize {
    let open = '{';
    let text = "}}}";
    let raw = r#"{ "quoted" }"#;
    /* a { nested /* } */ comment */
    s.len() + text.len() + raw.len() + usize::from(open == '\\'')
}

trait Shape {
    fn area(&self) -> f32;
    fn named(&self) -> &str {
        "shape"
    }
}

#[cfg(test)]
mod tests {
    fn helper_in_a_test_module() {
    }
}
'''


class Lengths(unittest.TestCase):
    def test_each_function_with_a_body_from_fn_to_its_brace(self):
        self.assertEqual(
            list(check.function_lengths(SOURCE)),
            [("three", 3, 3), ("literals", 7, 7), ("named", 17, 3)],
        )

    def test_blanking_keeps_every_line(self):
        self.assertEqual(check.blank_literals(SOURCE).count("\n"), SOURCE.count("\n"))


if __name__ == "__main__":
    unittest.main()
