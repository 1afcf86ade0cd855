"""Corrupted copies of a ULog file for the replay's robustness tests.

A ULog is a 16-byte header and then messages of ``size`` (uint16), ``type`` (one byte) and
``size`` bytes of payload. ``A`` (add logged message) binds ``msg_id`` (payload bytes 1-2) to a
topic name (bytes 3-); ``D`` (data) starts with that ``msg_id`` and then the sample, whose first
field is PX4's ``timestamp`` (uint64, µs)."""

import struct
from pathlib import Path

HEADER = 16


def messages(data: bytes) -> list[tuple[int, int, int]]:
    """``(offset of the payload, size, type)`` of each message, in file order."""
    found, offset = [], HEADER
    while offset + 3 <= len(data):
        size, kind = struct.unpack_from("<HB", data, offset)
        found.append((offset + 3, size, kind))
        offset += 3 + size
    return found


def data_offsets(data: bytes, topic: str) -> list[tuple[int, int]]:
    """``(payload offset, size)`` of each data message of ``topic`` (instance 0)."""
    ids = set()
    for start, size, kind in messages(data):
        if kind == ord("A") and data[start] == 0 and data[start + 3:start + size] == \
                topic.encode():
            ids.add(struct.unpack_from("<H", data, start + 1)[0])
    return [(start, size) for start, size, kind in messages(data)
            if kind == ord("D") and struct.unpack_from("<H", data, start)[0] in ids]


def shift_stamp(source: Path, target: Path, topic: str, index: int, shift_us: int) -> int:
    """Copy ``source`` with the time stamp of ``topic``'s sample ``index`` moved by
    ``shift_us``; returns the original stamp."""
    data = bytearray(source.read_bytes())
    start, _size = data_offsets(bytes(data), topic)[index]
    stamp = struct.unpack_from("<Q", data, start + 2)[0]
    struct.pack_into("<Q", data, start + 2, stamp + shift_us)
    target.write_bytes(bytes(data))
    return stamp


def without_topic(source: Path, target: Path, topic: str) -> None:
    """Copy ``source`` without any data message of ``topic`` (its format stays declared)."""
    data = source.read_bytes()
    dropped = {start for start, _size in data_offsets(data, topic)}
    kept = [data[:HEADER]] + [data[start - 3:start + size] for start, size, _kind
                              in messages(data) if start not in dropped]
    target.write_bytes(b"".join(kept))


def unknown_message_id(source: Path, target: Path, topic: str, index: int, msg_id: int) -> None:
    """Copy ``source`` with data message ``index`` of ``topic`` bound to ``msg_id``, an id no
    ``A`` message declares (pyulog prints a warning and skips it)."""
    data = bytearray(source.read_bytes())
    start, _size = data_offsets(bytes(data), topic)[index]
    struct.pack_into("<H", data, start, msg_id)
    target.write_bytes(bytes(data))
