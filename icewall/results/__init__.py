"""HDF5 result files of one analysis, written step by step (reference: docs/hdf5_layout.md).

Layout (format "icewall-result", format_version 1): root attributes (units, status, ...),
``/deck`` (deck text), ``/mesh/...`` (the Mesh), ``/history/<column>`` (one value per written
step) and ``/steps/<NNNNN>/{displacement, gauss/<field>}`` (fields of the steps that stored them).
A run writes ``<path>.partial`` and renames it to ``<path>`` when it completes or is stopped.
"""

from icewall.results.reader import ResultFile, open_result
from icewall.results.writer import FORMAT, FORMAT_VERSION, ResultWriter, StepRecord

__all__ = ["FORMAT", "FORMAT_VERSION", "ResultFile", "ResultWriter", "StepRecord",
           "open_result"]
