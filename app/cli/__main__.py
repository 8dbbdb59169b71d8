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
    from app.cli import main, stop_requested

    _rc = main()
    if stop_requested():
        # a KeyboardInterrupt that Python swallowed during the run (in a weakref callback
        # while importing) would make the interpreter kill itself with SIGINT at exit
        # instead of returning 128 + signal: leave now, everything is cleaned up already
        import os

        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_rc)
    sys.exit(_rc)
