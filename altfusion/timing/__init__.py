"""Multi-rate timing of a system's sensor streams, checked in a result from any host.

``altfusion timing`` (``docs/timing.md``): the streams and their declared schedules come from
the SSP (:mod:`.streams`), a result file is read in the layout its host writes
(:mod:`.table`), each stream is checked against the multi-rate convention of
``docs/signals.md`` (:mod:`.check`) and reported as a table (:mod:`.report`);
:mod:`.command` runs a system in a host first when asked to.
"""
