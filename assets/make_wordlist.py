"""Regenerate ``assets/wordlist.txt`` (developer tool; not run by the program).

Needs the ``wordfreq`` package (not a Lipspace dependency): ``pip install wordfreq``.
Run from the project root: ``python assets/make_wordlist.py``.

Method: candidates are the 20,000 most frequent English words (wordfreq) that are in
the CMU dictionary, alphabetic, and not on a short blocklist. The list starts with the
1,500 most frequent of them; words are then added greedily, each time the candidate
that brings the phone distribution of the list (every word weighted equally, as the
synthetic talker samples them) closest in Kullback-Leibler divergence to the
distribution of the paper's Table 1, until the list holds 3,000 words.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from engine.phonetics import PAPER_COUNTS, PAUSE, PHONES, UnknownWordError, pronounce  # noqa: E402

N_POOL, N_START, N_TOTAL = 20000, 1500, 3000
BLOCK = set("""
sex sexy sexual fuck fucking fucked fucker shit shitty bitch bitches ass asshole dick cock pussy
porn porno nude naked rape raped rapist nigga nigger fag faggot slut whore cunt damn hell bastard
kill killed killing killer murder suicide penis vagina boob boobs tits gay lesbian retard retarded
drug drugs cocaine heroin weed nazi hitler terrorist terror bomb gun guns shoot shooting dead death
die died breast breasts anal oral orgasm horny piss pissed crap jesus christ god lord allah
""".split())


def main() -> None:
    import wordfreq

    labels = [p for p in PHONES if p != PAUSE]
    idx = {p: i for i, p in enumerate(labels)}
    target = np.array([PAPER_COUNTS.get(p, 20) for p in labels], float)
    target /= target.sum()
    words, rows = [], []
    for w in wordfreq.top_n_list("en", N_POOL * 2):
        if len(words) >= N_POOL:
            break
        if not w.isalpha() or not w.isascii() or w in BLOCK or (len(w) < 2 and w not in ("a", "i")):
            continue
        try:
            ph = pronounce(w)
        except UnknownWordError:
            continue
        if not ph:
            continue
        v = np.zeros(len(labels))
        for p in ph:
            v[idx[p]] += 1
        words.append(w)
        rows.append(v)
    C = np.array(rows)
    chosen = list(range(N_START))
    free = np.ones(len(words), bool)
    free[:N_START] = False
    tot = C[:N_START].sum(0)
    while len(chosen) < N_TOTAL:
        cand = np.flatnonzero(free)
        new = tot[None, :] + C[cand]
        q = (new + 1e-3) / (new + 1e-3).sum(1, keepdims=True)
        kl = (target[None, :] * np.log(target[None, :] / q)).sum(1)
        best = cand[np.argmin(kl)]
        chosen.append(best)
        free[best] = False
        tot += C[best]
    q = tot / tot.sum()
    lines = [
        "# Word list of the synthetic talker (engine.synthetic): common English words in the",
        "# CMU dictionary, chosen so that their phones, every word weighted equally, are",
        "# distributed roughly like the paper's Table 1. Made by assets/make_wordlist.py.",
        f"# KL(Table 1 || list) = {(target * np.log(target / q)).sum():.4f}",
    ]
    lines += sorted(words[i] for i in chosen)
    (ROOT / "assets" / "wordlist.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
    for p in labels:
        print(f"{p:3s} paper {target[idx[p]]*100:5.2f}%  list {q[idx[p]]*100:5.2f}%")


if __name__ == "__main__":
    main()
