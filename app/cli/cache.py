"""``lipspace cache``: where the cache is and how big; ``--clear`` empties it."""
from __future__ import annotations

_KINDS = (("corpus", "synthetic talker corpora"), ("audio", "their speech audio"),
          ("manifold", "manifolds fitted to them"), ("method choice", "synthesis methods measured"),
          ("sound", "the explorer's sound"), ("density", "densities of drawn clouds"), ("partial", "unfinished writes"))


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
        after = entries(root)
        left = [e for e in after if e.owned]
        print(f"removed {len(gone)} entr{'y' if len(gone) == 1 else 'ies'} ({_mb(sum(e.size for e in gone))}) "
              f"from {root}" + (f"; {len(left)} could not be removed (in use or read-only)" if left else ""))
        _not_ours(after)
        return 0 if not left else 1
    found = [e for e in entries(root) if e.owned]
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
    _not_ours(entries(root))
    return 0


def _not_ours(found) -> None:
    """Say which files look like cache entries but were not written by this cache (they are never deleted)."""
    import sys

    others = [e for e in found if not e.owned]
    if others:
        names = ", ".join(e.path.name for e in others[:3]) + (" ..." if len(others) > 3 else "")
        print(f"lipspace cache: note: {len(others)} file{'s' * (len(others) != 1)} named like cache entries "
              f"({names}; {_mb(sum(e.size for e in others))}) {'were' if len(others) != 1 else 'was'} not written "
              "by this cache (none has Lipspace's marker) and stay; delete them yourself if they are yours to "
              "remove", file=sys.stderr)
