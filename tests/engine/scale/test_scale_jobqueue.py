"""The documented multi-node recipe (docs/ARCHITECTURE.md, dask-jobqueue) makes a valid job script; nothing is
submitted."""
import re
from pathlib import Path

import pytest

pytest.importorskip("dask_jobqueue")

DOC = Path(__file__).resolve().parents[3] / "docs" / "ARCHITECTURE.md"


def _recipe() -> str:
    """The ```python block of the architecture document whose first line is a '# recipe:' comment."""
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), flags=re.S)
    recipes = [b for b in blocks if b.lstrip().startswith("# recipe:")]
    assert len(recipes) == 1, f"expected one '# recipe:' block in {DOC.name}, found {len(recipes)}"
    return "\n".join(line[2:] if line.startswith("  ") else line for line in recipes[0].splitlines())


def test_documented_slurm_recipe_makes_a_job_script_for_one_worker():
    ns = {}
    exec(compile(_recipe(), f"{DOC.name} recipe", "exec"), ns)  # builds the cluster object: no job submitted
    cluster = ns["cluster"]
    try:
        script = cluster.job_script()
        assert script.startswith("#!/usr/bin/env bash")
        assert "#SBATCH --cpus-per-task=1" in script and "#SBATCH --mem=4G" in script
        assert "#SBATCH -t 02:00:00" in script
        worker = [line for line in script.splitlines() if "distributed.cli.dask_worker" in line]
        assert len(worker) == 1, script
        cmd = worker[0]
        assert cmd.startswith("/shared/lipspace/.venv/bin/python -m distributed.cli.dask_worker ")
        assert cluster.scheduler_address in cmd  # workers dial the scheduler this process runs
        assert "--nthreads 1" in cmd and "--memory-limit 4.00GiB" in cmd
        assert cluster.workers == {}  # nothing was asked of the batch system
    finally:
        cluster.close()
