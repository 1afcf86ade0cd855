"""The timing report: one table per stream, then the violations (``docs/timing.md``)."""

from altfusion.timing.check import TIME_TOLERANCE, ConsumerResult, Spread, StreamResult

OK, FAIL = "ok", "FAIL"


def _seconds(value: float) -> str:
    return f"{value:.4g} s"


def _spread(spread: Spread | None) -> str:
    if spread is None:
        return "-"
    if f"{spread.low:.4g}" == f"{spread.high:.4g}":
        return _seconds(spread.low)
    return f"{spread.low:.4g} .. {spread.high:.4g} s (mean {spread.mean:.4g})"


def _verdict(bad: int | bool) -> str:
    return FAIL if bad else OK


def _rows(result: StreamResult) -> list[tuple[str, str, str, str]]:
    """(check, measured, allowed, verdict) rows of one stream's table."""
    rows = [
        ("samples expected / seen", f"{result.expected} / {result.seen}", "", ""),
        ("no new measurement", f"{result.gaps} instants",
         f"while {result.stream.valid} false" if result.stream.valid else "0",
         _verdict(any(v.kind.startswith("samples missing") for v in result.violations))),
        ("counted twice", str(result.duplicated), "0", _verdict(result.duplicated)),
        ("shown before due", str(result.early), "0", _verdict(result.early)),
        ("late or lost", str(result.late), "0", _verdict(result.late)),
        ("stamp error", _seconds(result.stamp_error), f"<= {TIME_TOLERANCE:g} s",
         _verdict(result.stamp_error > TIME_TOLERANCE)),
        ("jitter", _seconds(result.jitter), f"<= {TIME_TOLERANCE:g} s",
         _verdict(result.jitter > TIME_TOLERANCE)),
        ("delivery (row - instant)", _spread(result.delay),
         f"{result.allowed_delay[0]:.4g} .. {result.allowed_delay[1]:.4g} s",
         _verdict(result.early or result.late)),
    ]
    rows += [_consumer_row(consumer, result.seen) for consumer in result.consumers]
    return rows


def _consumer_row(consumer: ConsumerResult, shown: int) -> tuple[str, str, str, str]:
    via = f" via {', '.join(consumer.consumer.relays)}" if consumer.consumer.relays else ""
    label = f"{consumer.consumer.column}{via}"
    if not consumer.recorded:
        return (label, "not recorded", "", "-")
    pending = f" ({consumer.pending} after the last row)" if consumer.pending else ""
    measured = (f"saw {consumer.seen} of {shown}{pending}, latency "
                f"{_spread(consumer.latency)}")
    return (label, measured, f"<= {consumer.allowed:.4g} s",
            _verdict(consumer.ahead or consumer.early or consumer.late or consumer.never))


def format_stream(result: StreamResult) -> str:
    """The table of one stream."""
    stream = result.stream
    title = (f"{stream.name} ({stream.fmu}): period {float(stream.period):g} s, offset "
             f"{float(stream.offset):g} s, latency {float(stream.latency):g} s, step "
             f"{stream.step:g} s")
    if not result.recorded:
        return (f"{title}\n  not recorded: no columns {stream.count_column} and "
                f"{stream.time_column}\n")
    rows = [("check", "measured", "allowed", "")] + _rows(result)
    widths = [max(len(row[i]) for row in rows) for i in range(3)]
    lines = [f"{title}; rows every {result.interval:g} s"]
    lines += ["  " + "  ".join(cell.ljust(width) for cell, width in zip(row, widths,
                                                                          strict=False))
              + f"  {row[3]}" for row in rows]
    lines += [f"  note: {note}" for note in result.notes]
    return "\n".join(line.rstrip() for line in lines) + "\n"


def format_report(results: list[StreamResult]) -> str:
    """Every stream's table, then the verdict and the violations."""
    parts = [format_stream(result) for result in results]
    violations = [v for result in results for v in result.violations]
    checked = [r for r in results if r.recorded]
    if violations:
        parts.append(f"{len(violations)} violation(s) in "
                     f"{sum(not r.ok for r in checked)} of {len(checked)} streams:")
        parts += [f"  {violation}" for violation in violations]
    else:
        parts.append(f"all {len(checked)} recorded streams hold their declared timing")
    return "\n".join(parts)
