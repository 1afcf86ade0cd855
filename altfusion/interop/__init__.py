"""Our systems and FMUs in third-party tools: the FMI edge towards other engines.

* :mod:`~altfusion.interop.osp` exports a system as an ``OspSystemStructure.xml`` folder
  (libcosim's own configuration format, with per-component step sizes);
* :mod:`~altfusion.interop.engines` runs an SSP (or OSP folder) in libcosim (``libcosimpy``),
  ECOS (``ecospy``, in process, or its command-line host with every FMU in a proxy process) and
  returns the recorded trajectories as :class:`~altfusion.cosim.Results`;
* :mod:`~altfusion.interop.container` packs a subsystem into one FMU with
  ``fmu-manipulation-toolbox``;
* :mod:`~altfusion.interop.compliance` checks FMUs (fmpy, the toolbox's FMI 2.0 checker) and SSP
  files (SSP 1.0 schemas, OSP annotations) without network access.

The third-party packages are the ``interop`` extra; each module imports them only when used.
"""
