"""The remote-centre-compliance device as a 3-D pin-jointed truss (docs/rcc.md): scenes of kind
'rcc' (`case.py`), the truss models (`device.py`, `truss.py`) and `femcontact rcc` (`cli.py`)."""
from femcontact.config.schema import describe
from femcontact.families.family import Family
from femcontact.families.rcc import case


def _schema_sections() -> list[tuple[str, list[tuple], str]]:
    return [("## RCC scene (kind = rcc)", describe(case.SCHEMA), "Example: [`scenes/rcc.toml`](../scenes/rcc.toml).")]


FAMILY = Family(name="rcc", doc="docs/rcc.md", kinds=("rcc",), resolve=case.resolve, run_case=case.run_case,
                schema_sections=_schema_sections,
                primary_columns=("max_rel_error", "worst_dof", "centre_z", "centre_z_moved"))
