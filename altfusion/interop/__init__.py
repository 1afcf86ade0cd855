"""Our systems and FMUs in third-party tools: the FMI edge towards other engines.

* :mod:`~altfusion.interop.osp` exports a system as an ``OspSystemStructure.xml`` folder
  (libcosim's own configuration format, with per-component step sizes);
* :mod:`~altfusion.interop.engines` runs an SSP (or OSP folder) in libcosim (``libcosimpy``)
  and ECOS (``ecospy``) and returns the recorded trajectories as
  :class:`~altfusion.cosim.Results`;
* :mod:`~altfusion.interop.proxy` runs it in ECOS's command-line host, a program without
  Python, with every FMU in its own ``proxyfmu`` process and libpython preloaded;
* :mod:`~altfusion.interop.delays` sets the estimators' sensor delays a Jacobi-type master
  (libcosim, ECOS) needs: each sample is one step of its sensor older than its stamp;
* :mod:`~altfusion.interop.container` packs a subsystem into one FMU with
  ``fmu-manipulation-toolbox``;
* :mod:`~altfusion.interop.compliance` checks FMUs (fmpy, the toolbox's FMI 2.0 checker) and SSP
  files (SSP 1.0 schemas, OSP annotations) without network access.

The third-party packages are the ``interop`` extra; each module imports them only when used.
Importing this package loads the native libraries they need from the environment
(:mod:`~altfusion.interop.native`).
"""

from altfusion.interop.native import preload_engine_libraries

preload_engine_libraries()
