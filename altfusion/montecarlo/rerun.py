"""Re-running one run of a campaign alone, in this process: it gives the same numbers as in
the campaign (the seeds depend only on the master seed, the run index and the component)."""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.montecarlo.campaign import build_manifest, check_same_campaign, plan
from altfusion.montecarlo.execution import CampaignSettings
from altfusion.montecarlo.source import CampaignError, SystemSource
from altfusion.montecarlo.storage import (
    RunRecord,
    has_manifest,
    read_manifest,
    read_run,
    run_path,
)
from altfusion.montecarlo.worker import execute_run


@dataclass
class Rerun:
    record: RunRecord
    stored: RunRecord | None
    """The campaign's stored copy of the run, if there is one."""

    @property
    def identical(self) -> bool | None:
        """Whether the re-run equals the stored run bit for bit (None: nothing to compare)."""
        if self.stored is None:
            return None
        mine, theirs = self.record.results, self.stored.results
        return (self.record.seeds == self.stored.seeds
                and list(mine.columns) == list(theirs.columns)
                and np.array_equal(mine.time, theirs.time)
                and all(np.array_equal(mine[n], theirs[n]) for n in mine.columns))


def rerun(source: SystemSource, index: int, settings: CampaignSettings | None = None,
          out: Path | None = None) -> Rerun:
    """Run ``index`` alone. If ``out`` holds a campaign, its settings are used (unset ones) and
    checked (set ones), and the run is compared with the campaign's copy."""
    if index < 0:
        raise CampaignError(f"run index must be >= 0, got {index}")
    settings = settings or CampaignSettings()
    stored = read_manifest(out) if out is not None and has_manifest(out) else None
    settings = CampaignSettings(1, settings.master_seed, settings.stop_time,
                                settings.parameters).resolved(stored)
    task, prepared = plan(source, settings.master_seed, settings.stop_time, settings.parameters)
    if stored is not None:
        check_same_campaign(stored, build_manifest(task, prepared, 1))
    record = execute_run(task, index)
    stored_run = read_run(out, index) if stored is not None and run_path(out, index).is_file() \
        else None
    return Rerun(record, stored_run)
