"""`python -m app.cli` is the `lipspace` command."""
import signal
import sys


def _stopped_early(signum, frame):
    """Ctrl-C, SIGTERM or SIGHUP while Python is still importing: nothing was started."""
    name = signal.Signals(signum).name
    what = "interrupted" if signum == signal.SIGINT else f"stopped by {name}"
    print(f"lipspace: {what}; nothing was written.", file=sys.stderr)
    raise SystemExit(128 + signum)


if __name__ == "__main__":
    for _sig in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None)):
        if _sig is not None:
            signal.signal(_sig, _stopped_early)
    from app.cli import main

    sys.exit(main())
