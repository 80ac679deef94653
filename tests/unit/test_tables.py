"""The one Markdown-table writer (femcontact/outputs/tables.py) of every report."""
from femcontact.outputs.tables import format_value, markdown_table


def test_a_table_is_a_header_a_separator_and_one_line_per_row():
    lines = markdown_table(["case", "error", "dofs", "flag", "pose"],
                           [["a|b", 1.23456, 632, True, [0.5, 2.0]], ["line\nbreak", None, 10, False, []]],
                           formats=[None, "{:+.2f} %", None, None, None], align="lrrcl")
    assert lines == ["| case | error | dofs | flag | pose |",
                     "|:---|---:|---:|:---:|:---|",
                     "| a\\|b | +1.23 % | 632 | yes | (0.5, 2) |",
                     "| line break |  | 10 | no | none |"]


def test_values_without_a_format_have_four_significant_digits():
    assert markdown_table(["x"], [[1 / 3], ["as given"]])[1:] == ["|---|", "| 0.3333 |", "| as given |"]
    assert format_value(12345.678) == "1.235e+04" and format_value([7]) == "7" and format_value(None) == ""
