"""Parameter studies: many variants of one case, run on this machine or on a Dask cluster.

``read_study`` reads a study file (``design``), ``run_study`` runs its variants (``run``),
``write_table`` writes the study table (``table``) and ``plot_study`` its pictures
(``pictures``). ``wrinkle study STUDY.toml --out DIR`` does all four (docs/studies.md).
"""

from wrinkle.studies.design import Parameter, Study, StudyError, read_study
from wrinkle.studies.run import run_study, run_variant
from wrinkle.studies.table import write_table

__all__ = [
    "Parameter",
    "Study",
    "StudyError",
    "read_study",
    "run_study",
    "run_variant",
    "write_table",
]
