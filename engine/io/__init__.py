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

Every name loads its module on first use, so ``import engine.io`` is light.
"""
from __future__ import annotations

from engine._lazy import lazy_names

#: public name -> the module that defines it
_WHERE = {
    **dict.fromkeys(('ImportFormatError',), 'engine.io.errors'),
    **dict.fromkeys(('read_alignment', 'read_lab', 'read_textgrid'), 'engine.io.readers.alignment'),
    **dict.fromkeys(('concat',), 'engine.io.combine'),
    **dict.fromkeys(('FORMATS', 'detect_format', 'read_corpus'), 'engine.io.dispatch'),
    **dict.fromkeys(('read_ema', 'read_est_track'), 'engine.io.readers.ema'),
    **dict.fromkeys(('write_est_track',), 'engine.io.writers.est_track'),
    **dict.fromkeys(('corpus_columns', 'point_columns', 'write_mesh_sequence', 'write_table_csv',
                     'write_trajectory_csv', 'write_trajectory_npy'), 'engine.io.writers.export'),
    **dict.fromkeys(('read_csv_landmarks',), 'engine.io.readers.landmarks'),
    **dict.fromkeys(('read_c3d',), 'engine.io.readers.markers'),
    **dict.fromkeys(('read_mesh_sequence', 'read_vertex_array'), 'engine.io.readers.mesh'),
    **dict.fromkeys(('read_mesh', 'read_obj', 'read_ply', 'read_vertex_labels'), 'engine.io.readers.meshfile'),
    **dict.fromkeys(('write_obj', 'write_ply'), 'engine.io.writers.meshfile'),
    **dict.fromkeys(('read_matrix',), 'engine.io.readers.matrix'),
    **dict.fromkeys(('read_pos', 'read_wave'), 'engine.io.readers.articulograph'),
    **dict.fromkeys(('read_mview', 'read_mview_audio'), 'engine.io.readers.mview'),
    **dict.fromkeys(('write_audio',), 'engine.io.writers.audio'),
    **dict.fromkeys(('resample',), 'engine.io.rates'),
    **dict.fromkeys(('MOTION_RATE_RANGE', 'AUDIO_RATE_RANGE'), 'engine.io._util'),
}
__all__ = list(_WHERE)
__getattr__, __dir__ = lazy_names("engine.io", _WHERE, globals())
