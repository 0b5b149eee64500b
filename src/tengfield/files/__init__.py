"""Every file tengfield writes goes through this package (issue #41): the primitives
that each result's writer (``io.py``, ``*/output.py``, ``field/io.py``) composes.

* :mod:`.atomic`: one file, never half written (``atomic_path``, ``write_bytes``),
  never into a pipe or device or through a symlink (``writable_target``); the inputs
  an output directory must keep (``note_input``);
* :mod:`.text`: ``write_text``, ``write_json`` (strict JSON), ``scene_toml``;
  ``one_line``, the one escaping of a user-supplied text quoted into a line of a file
  (``comment_lines``: a header as comment lines);
* :mod:`.tables`: CSV (``write_csv``: numbers, Arrow; ``write_rows``: text cells);
* :mod:`.hdf5`: run.h5 (``write_tables``, ``read_tables``, ``MAX_CSV_ROWS``) and
  Debian's ``h5py`` (``import_h5py``);
* :mod:`.figures`: ``--figure-format`` / ``--dpi`` (``figure_file``, ``figure_dpi``)
  and ``write_figure``;
* :mod:`.directory`: the ``-o DIR`` directories, checked first, staged, locked and
  moved into place all or nothing (``StagedOutput``).
"""
from .atomic import (atomic_path, file_kind, forget_inputs, input_named, note_input,
                     writable_target, write_bytes)
from .figures import (DPI_RANGE, FIGURE_FORMATS, figure_dpi, figure_file, set_figure_dpi,
                      set_figure_format, write_figure)
from .tables import FORMAT_BLOCK_ROWS, write_csv, write_rows
from .text import (comment_lines, one_line, scene_dir, scene_toml, toml_key, toml_value,
                   write_json, write_text)

__all__ = ["atomic_path", "file_kind", "forget_inputs", "input_named", "note_input",
           "writable_target", "write_bytes", "DPI_RANGE", "FIGURE_FORMATS", "figure_dpi",
           "figure_file", "set_figure_dpi", "set_figure_format", "write_figure",
           "FORMAT_BLOCK_ROWS", "write_csv", "write_rows", "comment_lines", "one_line",
           "scene_dir", "scene_toml", "toml_key", "toml_value", "write_json", "write_text"]
