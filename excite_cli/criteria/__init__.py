"""The criteria an excitation trajectory is optimized for, one record each (:mod:`.catalogue`), beside
the constraints it must meet (:mod:`excite_cli.constraints`)."""

from excite_cli.criteria.catalogue import CRITERIA, NAMES, criterion_record
from excite_cli.criteria.record import CriterionRecord

__all__ = ["CRITERIA", "NAMES", "CriterionRecord", "criterion_record"]
