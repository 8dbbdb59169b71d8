"""What every benchmark prints beside its figures (the BLAS kernel in use, memory), how it runs a
child measurement, and the speech it times synthesis on.

The scripts run as ``python benchmarks/NAME.py``, so this folder is on ``sys.path``.
"""
from __future__ import annotations

import os


def blas_record() -> dict:
    """Every BLAS library loaded (threadpoolctl) with its kernel and threads, and the OPENBLAS_*
    variables set in the environment (OPENBLAS_CORETYPE / OPENBLAS_L2_SIZE pick the kernel on
    these machines)."""
    from threadpoolctl import threadpool_info

    libs = [{"api": i.get("internal_api"), "version": i.get("version"), "kernel": i.get("architecture"),
             "threads": i.get("num_threads")} for i in threadpool_info() if i.get("user_api") == "blas"]
    env = {k: v for k, v in sorted(os.environ.items()) if k.startswith("OPENBLAS_")}
    return {"libraries": libs, "openblas_env": env}


def blas_text(record: dict) -> str:
    """One line of a :func:`blas_record`."""
    libs = "; ".join(f"{x['api']} {x['version']} kernel={x['kernel']} threads={x['threads']}"
                     for x in record["libraries"]) or "none found"
    env = " ".join(f"{k}={v}" for k, v in record["openblas_env"].items()) or "unset"
    return f"{libs}; OPENBLAS_* env {env}"


def blas_kernel() -> str:
    """Every BLAS library loaded, with its kernel and threads, and the OPENBLAS_* setting."""
    return blas_text(blas_record())


def _status_mb(field: str, pid="self") -> float:
    """One memory field of /proc/PID/status (MiB; NaN where there is none)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")


def current_rss_mb() -> float:
    """Resident memory of this process now (MiB), from /proc (NaN where there is none)."""
    return _status_mb("VmRSS")


def peak_rss_mb(pid="self") -> float:
    """Peak resident memory (VmHWM, MiB) of this process or of process ``pid``, from /proc
    (NaN where there is none); unlike getrusage's maximum it does not survive exec from the parent."""
    return _status_mb("VmHWM", pid)


def run_child_json(cmd, **kwargs):
    """Run a benchmark's child process and return the JSON value it printed on its last stdout line.

    Parameters
    ----------
    cmd : sequence of str or path
        The command (``[sys.executable, __file__, "--child", ...]``).
    **kwargs
        Passed to :func:`subprocess.run` (``env``, ``cwd``, ``timeout``: a timeout raises
        :class:`subprocess.TimeoutExpired`).

    Raises
    ------
    SystemExit
        When the child exits non-zero or prints nothing: its command and the end of its stderr.
    """
    import json
    import subprocess

    cmd = [str(c) for c in cmd]
    r = subprocess.run(cmd, capture_output=True, text=True, **kwargs)
    lines = r.stdout.strip().splitlines()
    if r.returncode == 0 and lines:
        return json.loads(lines[-1])
    why = f"exit {r.returncode}" if r.returncode else "printed nothing"
    raise SystemExit(f"{' '.join(cmd)}: failed ({why})\n{r.stderr[-3000:]}")


def first_phones(corpus, seconds: float):
    """``([(label, duration s), ...], utterance)``: the phones of the first ``seconds`` of the
    corpus's longest utterance, the last one cut at ``seconds``."""
    u = max(corpus.utterances, key=lambda x: x.n_frames)
    out, t = [], 0.0
    for p in u.phones:
        d = min(p.end - p.start, seconds - t)
        if d <= 0:
            break
        out.append((p.label, d))
        t += d
    return out, u
