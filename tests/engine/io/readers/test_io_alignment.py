"""Phone alignments: Praat TextGrid (long, short, binary), HTK / MOCHA .lab, xlabel, TIMIT .phn."""
import struct

import pytest

from engine.io import ImportFormatError, read_alignment, read_lab, read_textgrid

LONG = '''File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 1.2
tiers? <exists>
size = 2
item []:
    item [1]:
        class = "IntervalTier"
        name = "words"
        xmin = 0
        xmax = 1.2
        intervals: size = 1
        intervals [1]:
            xmin = 0
            xmax = 1.2
            text = "mama"
    item [2]:
        class = "IntervalTier"
        name = "{tier}"
        xmin = 0
        xmax = 1.2
        intervals: size = 5
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = ""
        intervals [2]:
            xmin = 0.1
            xmax = 0.35
            text = "m"
        intervals [3]:
            xmin = 0.35
            xmax = 0.6
            text = "AA1"
        intervals [4]:
            xmin = 0.6
            xmax = 0.8
            text = "m"
        intervals [5]:
            xmin = 0.8
            xmax = 1.2
            text = "AH0"
'''

SHORT = '''File type = "ooTextFile"
Object class = "TextGrid"

0
1.2
<exists>
1
"IntervalTier"
"phones"
0
1.2
3
0
0.5
"p"
0.5
0.9
"a"
0.9
1.2
""
'''


def _binary_textgrid(intervals, name="phones"):
    out = b"ooBinaryFile\x08TextGrid" + struct.pack(">2d?i", 0.0, intervals[-1][1], True, 1)
    out += struct.pack("B", 12) + b"IntervalTier" + struct.pack(">h", len(name)) + name.encode()
    out += struct.pack(">2di", 0.0, intervals[-1][1], len(intervals))
    for s, e, lab in intervals:
        out += struct.pack(">2d", s, e) + struct.pack(">h", len(lab)) + lab.encode()
    return out


def test_long_textgrid_picks_the_phone_tier_and_keeps_labels(tmp_path):
    p = tmp_path / "a.TextGrid"
    p.write_text(LONG.format(tier="phones"))
    ph = read_textgrid(p)
    assert [x.label for x in ph] == ["m", "AA1", "m", "AH0"]  # empty interval left out, labels as given
    assert ph[0].start == pytest.approx(0.1) and ph[-1].end == pytest.approx(1.2)
    assert read_alignment(p) == ph


@pytest.mark.parametrize("name", ["Phones", "PHONE", "segments", "spk1 - phones"])
def test_phone_tier_names_are_recognised(tmp_path, name):
    p = tmp_path / "a.TextGrid"
    p.write_text(LONG.format(tier=name))
    assert len(read_textgrid(p)) == 4


def test_explicit_tier_and_ambiguous_tiers(tmp_path):
    p = tmp_path / "a.TextGrid"
    p.write_text(LONG.format(tier="aligned"))
    with pytest.raises(ImportFormatError, match="cannot tell which tier.*'words'.*'aligned'"):
        read_textgrid(p)
    assert [x.label for x in read_textgrid(p, tier="words")] == ["mama"]
    assert len(read_textgrid(p, tier="ALIGNED")) == 4
    with pytest.raises(ImportFormatError, match="no tier named 'nope'"):
        read_textgrid(p, tier="nope")


def test_short_and_binary_and_utf16_textgrids(tmp_path):
    p = tmp_path / "s.TextGrid"
    p.write_text(SHORT)
    assert [(x.start, x.end, x.label) for x in read_textgrid(p)] == [(0.0, 0.5, "p"), (0.5, 0.9, "a")]
    b = tmp_path / "b.TextGrid"
    b.write_bytes(_binary_textgrid([(0.0, 0.25, "s"), (0.25, 0.75, "iy")]))
    assert [x.label for x in read_alignment(b)] == ["s", "iy"]
    u = tmp_path / "u.TextGrid"
    u.write_bytes(LONG.format(tier="phones").encode("utf-16"))  # Praat writes UTF-16 with a BOM
    assert len(read_textgrid(u)) == 4


def test_broken_textgrid_names_the_line(tmp_path):
    lines = LONG.format(tier="phones").split("\n")
    k = next(i for i, s in enumerate(lines) if "xmax = 0.35" in s)
    lines[k] = "            xmax = zero point three"
    p = tmp_path / "bad.TextGrid"
    p.write_text("\n".join(lines))
    with pytest.raises(ImportFormatError) as e:
        read_textgrid(p)
    assert e.value.line == k + 1 and "bad.TextGrid, line" in str(e.value) and "xmax" in str(e.value)
    t = tmp_path / "trunc.TextGrid"
    t.write_text("\n".join(LONG.format(tier="phones").split("\n")[:30]))
    with pytest.raises(ImportFormatError, match="line 31: .*the file ends"):
        read_textgrid(t)
    h = tmp_path / "nohead.TextGrid"
    h.write_text("xmin = 0\n")
    with pytest.raises(ImportFormatError, match="line 1: not a Praat TextGrid"):
        read_textgrid(h)


def test_textgrid_nan_and_disorder_are_errors(tmp_path):
    p = tmp_path / "n.TextGrid"
    p.write_text(SHORT.replace("0.5\n0.9", "nan\n0.9"))
    with pytest.raises(ImportFormatError, match="interval 2.*finite"):
        read_textgrid(p)


def test_mocha_lab_in_seconds(tmp_path):
    p = tmp_path / "a.lab"
    p.write_text("0 0.25 sil\n0.25 0.28 breath\n0.28 0.35 sil\n")
    ph = read_lab(p)
    assert [(x.start, x.end, x.label) for x in ph] == [(0, 0.25, "sil"), (0.25, 0.28, "breath"), (0.28, 0.35, "sil")]


def test_htk_units_detected_and_forced(tmp_path):
    p = tmp_path / "h.lab"
    p.write_text("0 2500000 sil\n2500000 3100000 m -12.5\n3100000 5000000 aa\n")
    ph = read_lab(p)
    assert [x.label for x in ph] == ["sil", "m", "aa"]
    assert ph[1].start == pytest.approx(0.25) and ph[1].end == pytest.approx(0.31) and ph[2].end == pytest.approx(0.5)
    q = tmp_path / "small.lab"
    q.write_text("0 1 a\n1 3 b\n")  # small integers: seconds
    assert read_lab(q)[1].end == 3.0
    assert read_lab(q, units="htk")[1].end == pytest.approx(3e-7)


def test_xlabel_and_timit_phn(tmp_path):
    x = tmp_path / "x.lab"
    x.write_text("signal fsew0_001\ntype 0\ncolor 121\nfont -misc-*\nseparator ;\nnfields 1\n#\n"
                 "    0.2500  121 sil\n    0.3100  121 m\n    0.5000  121 aa\n")
    ph = read_lab(x)
    assert [(x.start, x.end, x.label) for x in ph] == [(0, 0.25, "sil"), (0.25, 0.31, "m"), (0.31, 0.5, "aa")]
    t = tmp_path / "a.phn"
    t.write_text("0 3200 h#\n3200 4800 sh\n")
    ph = read_alignment(t)
    assert ph[1].start == pytest.approx(0.2) and ph[1].end == pytest.approx(0.3)


@pytest.mark.parametrize("text, line, match", [
    ("0 0.2 a\n0.2 b\n", 2, "expected 'start end label'"),
    ("0 0.2 a\n0.2 x0.3 b\n", 2, "column 2 is 'x0.3'"),
    ("0 0.2 a\n0.3 0.25 b\n", 2, "ends at 0.25 s before it starts"),
    ("0 0.4 a\n0.3 0.5 b\n", 2, "before the previous label ends"),
    ("0 0.2 a\nnan 0.5 b\n", 2, "not finite"),
    ("# comment\n\n-1 0.2 a\n", 3, "expected a time >= 0"),
])
def test_lab_errors_name_the_line(tmp_path, text, line, match):
    p = tmp_path / "e.lab"
    p.write_text(text)
    with pytest.raises(ImportFormatError, match=match) as e:
        read_lab(p)
    assert e.value.line == line and f"e.lab, line {line}:" in str(e.value)


def test_binary_garbage_and_empty_labels(tmp_path):
    p = tmp_path / "g.lab"
    p.write_bytes(b"0 0.1 a\n\xff\xfe\x00garbage")
    with pytest.raises(ImportFormatError, match="line 2"):
        read_lab(p)
    e = tmp_path / "empty.lab"
    e.write_text("\n# nothing\n")
    with pytest.raises(ImportFormatError, match="holds no labels"):
        read_lab(e)
    with pytest.raises(FileNotFoundError):
        read_alignment(tmp_path / "missing.lab")
