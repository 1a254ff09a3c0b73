"""Fleets at scale: records of many assets through :class:`~prognosis.fleet.FleetMonitor`, on Dask, to Parquet.

* :class:`FleetSpec` (:mod:`.spec`): the job as names, numbers and paths, the only thing shipped with
  each shard; a worker builds the ARRs and the monitor from it once;
* sources (:mod:`.sources`): a directory of CSV files (one per asset) or one Parquet file;
* :func:`run_fleet` (:mod:`.engine`): shards of sorted asset ids on a local Dask cluster, a remote
  scheduler, or in this process; :func:`run_shard` is one task;
* :func:`read_fleet` (:mod:`.store`): the Parquet tables back as a :class:`~prognosis.fleet.FleetResult`;
* :func:`fleet_page` (:mod:`.page`): the overview page ``index.html``, offline, for 10^4 assets within
  20 MB; :func:`read_page_data` reads its data back;
* the output directory (:mod:`.outdir`): one run at a time (a lock), shards staged, tables published
  whole with a manifest, an interrupted run resumed.

Dask (``dask[distributed]``) and pyarrow are the optional extra ``[dask]``; ``prognosis`` uses
neither.  ``bgphm fleet`` is the command line of :func:`run_fleet`; ``docs/fleet.md`` is the guide.
"""

from .engine import SERIAL, default_shard_size, local_cluster, plan, run_fleet, run_shard, shard_assets
from .page import fleet_page, read_page_data
from .sources import CsvDirectory, ParquetRecords, open_source
from .spec import FleetSpec, model_reference, monitor_for
from .store import BUCKETS, bucket_of, read_fleet

__all__ = ["BUCKETS", "SERIAL", "CsvDirectory", "FleetSpec", "ParquetRecords", "bucket_of", "default_shard_size",
           "fleet_page", "local_cluster", "model_reference", "monitor_for", "open_source", "plan", "read_fleet",
           "read_page_data", "run_fleet", "run_shard", "shard_assets"]
