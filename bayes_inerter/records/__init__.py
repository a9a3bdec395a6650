"""Records: the generator, the CSV format and its reader, signal conditioning."""

from .conditioning import LOWPASS_HZ, fit_accuracy, lowpass
from .generator import GeneratorSettings, generate_record, paper_grid
from .io import COLUMNS, MIN_SAMPLES, RecordError, metadata_path, read_record, write_record
from .record import Record

__all__ = [
    "LOWPASS_HZ",
    "fit_accuracy",
    "lowpass",
    "GeneratorSettings",
    "generate_record",
    "paper_grid",
    "COLUMNS",
    "MIN_SAMPLES",
    "RecordError",
    "metadata_path",
    "read_record",
    "write_record",
    "Record",
]
