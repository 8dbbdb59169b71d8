"""``lipspace cache``: where the cache is and how big; ``--clear`` empties it."""
from __future__ import annotations

_KINDS = (("corpus", "synthetic talker corpora"), ("audio", "their speech audio"),
          ("manifold", "manifolds fitted to them"), ("method choice", "synthesis methods measured"),
          ("partial", "unfinished writes"))


def add_arguments(p):
    p.add_argument("--clear", action="store_true",
                   help="delete every cached corpus and manifold (they are rebuilt when next needed)")


def _mb(n: int) -> str:
    return f"{n / 1e6:.1f} MB"


def run(args) -> int:
    from app.files.cache import cache_dir, clear, entries

    root = cache_dir()
    if args.clear:
        gone = clear(root)
        left = entries(root)
        print(f"removed {len(gone)} entr{'y' if len(gone) == 1 else 'ies'} ({_mb(sum(e.size for e in gone))}) "
              f"from {root}" + (f"; {len(left)} could not be removed (in use or read-only)" if left else ""))
        return 0 if not left else 1
    found = entries(root)
    print(f"cache folder {root}" + ("" if root.is_dir() else " (not created yet)")
          + "  (set LIPSPACE_CACHE_DIR to use another folder)")
    for kind, label in _KINDS:
        mine = [e for e in found if e.kind == kind]
        if mine:
            presets = sorted({e.preset for e in mine if e.preset})
            print(f"  {label:26s} {len(mine):3d}  {_mb(sum(e.size for e in mine)):>10s}"
                  + (f"  ({', '.join(presets)})" if presets else ""))
    print(f"total {_mb(sum(e.size for e in found))}; 'lipspace cache --clear' deletes it (rebuilt when next "
          "needed)")
    return 0
