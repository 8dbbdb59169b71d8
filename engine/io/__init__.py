"""Data in and out: foreign corpus formats, phone alignments, resampling, exporters.

Readers (each returns a :class:`engine.recordings.corpus.Corpus` of one utterance per file, or a
list of :class:`engine.recordings.corpus.PhoneInterval` for alignments) raise
:class:`ImportFormatError` naming the file and the line or frame:

======================  ===============================================================
``read_corpus``          any format below, chosen by extension / content; several files
``read_ema``             MOCHA-TIMIT ``.ema`` (EST Track binary/ASCII, ASCII table), 2-D
``read_mview``           Haskins / MVIEW ``.mat`` structs, 3-D
``read_c3d``             C3D markers, 3-D
``read_mesh_sequence``   OBJ / PLY, one file per frame
``read_csv_landmarks``   OpenFace / named / long CSV landmark tracks
``read_vertex_array``    ``.npy`` vertex arrays + template mesh (VOCASET-style)
``read_matrix``          plain numeric matrices (.mat variable, .npy, CSV/TSV without names)
                         through a sensor layout (:mod:`engine.recordings.layouts`), 3-D
``read_pos``             Carstens AG500 / AG501 ``.pos`` binaries, 3-D
``read_wave``            NDI Wave TSV exports, 3-D
``read_alignment``       Praat TextGrid, HTK / MOCHA ``.lab``, ESPS xlabel, TIMIT ``.phn``
======================  ===============================================================

``resample`` changes the frame rate per utterance, ``concat`` joins corpora, and
:mod:`engine.io.writers.export` writes trajectories, mesh sequences and tables atomically.
Heavy third-party readers (scipy.io, c3d, textgrids) are imported only when used.
"""
from engine.io.errors import ImportFormatError
from engine.io.readers.alignment import read_alignment, read_lab, read_textgrid
from engine.io.combine import concat
from engine.io.dispatch import FORMATS, detect_format, read_corpus
from engine.io.readers.ema import read_ema, read_est_track, write_est_track
from engine.io.writers.export import (corpus_columns, point_columns, write_mesh_sequence, write_table_csv,
                              write_trajectory_csv, write_trajectory_npy)
from engine.io.readers.landmarks import read_csv_landmarks
from engine.io.readers.markers import read_c3d
from engine.io.readers.mesh import read_mesh_sequence, read_vertex_array
from engine.io.readers.meshfile import read_mesh, read_obj, read_ply, read_vertex_labels, write_obj, write_ply
from engine.io.readers.matrix import read_matrix
from engine.io.readers.articulograph import read_pos, read_wave
from engine.io.readers.mview import read_mview, read_mview_audio, write_audio
from engine.io.resample import resample

__all__ = [
    "ImportFormatError", "read_corpus", "detect_format", "FORMATS", "read_alignment", "read_textgrid", "read_lab",
    "read_ema", "read_est_track", "write_est_track", "read_mview", "read_mview_audio", "write_audio", "read_c3d",
    "read_mesh_sequence", "read_vertex_array", "read_mesh", "read_obj", "read_ply", "write_obj", "write_ply",
    "read_vertex_labels",
    "read_csv_landmarks", "read_matrix", "read_pos", "read_wave", "resample", "concat", "write_trajectory_csv", "write_trajectory_npy",
    "write_mesh_sequence", "write_table_csv", "point_columns", "corpus_columns",
]
