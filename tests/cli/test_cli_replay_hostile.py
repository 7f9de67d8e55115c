"""``pyrobots-aio replay`` on files crafted to hurt it (issue 26): one line, bounded memory.

Each case runs the command in a subprocess limited to 1 GiB of address space,
with a hang guard (``timeout``): it must end in one line on stderr naming the
file (and where in it), exit status 1, and no traceback. The MCAP files are
written record by record here, so that their chunks can lie about their size.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from pathlib import Path

LIMIT = 1 << 30
"""Address space given to the command: a bomb that inflated would not fit."""
RUN = (
    "import resource, runpy, sys; "
    f"resource.setrlimit(resource.RLIMIT_AS, ({LIMIT}, {LIMIT})); "
    "runpy.run_module('pyrobots_aio.cli', run_name='__main__')"
)
MAGIC = b"\x89MCAP0\r\n"
HEADER = {"format": "pyrobots_aio.recording", "version": 2, "t0": 0.0}
BLOCK = 128 * 1024
COVERS = " (the summary covers the 0 events before it)"


def _replay(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", RUN, "replay", *args],
        capture_output=True,
        text=True,
        timeout=120,  # a hang guard only: each case takes about a second
        check=False,
    )


def _record(opcode: int, body: bytes) -> bytes:
    return struct.pack("<BQ", opcode, len(body)) + body


def _text(value: str) -> bytes:
    data = value.encode()
    return struct.pack("<I", len(data)) + data


def _start() -> bytes:
    """An MCAP file up to its first chunk: magic, header, the pyrobots_aio metadata."""
    pairs = b"".join(_text(k) + _text(json.dumps(v)) for k, v in HEADER.items())
    metadata = _record(0x0C, _text("pyrobots_aio") + struct.pack("<I", len(pairs)) + pairs)
    return MAGIC + _record(0x01, _text("") + _text("test")) + metadata


def _chunk(compression: str, data: bytes, declared: int) -> bytes:
    fields = struct.pack("<QQQI", 0, 0, declared, 0) + _text(compression)
    return _record(0x06, fields + struct.pack("<Q", len(data)) + data)


def _file(path: Path, chunk: bytes) -> int:
    """Write an MCAP file holding ``chunk``; return the chunk's byte offset."""
    start = _start()
    footer = _record(0x02, struct.pack("<QQI", 0, 0, 0))
    path.write_bytes(start + chunk + footer + MAGIC)
    return len(start)


def _zeros_zstd(size: int) -> bytes:
    """A zstd frame of ``size`` zero bytes (a multiple of `BLOCK`), as run-length blocks.

    Four bytes of frame per 128 KiB: 2 GiB takes 64 KiB, and no time to make.
    Its header gives its size, as zstd's compressor writes it.
    """
    blocks = size // BLOCK
    # The magic number; an 8-byte size follows the window (128 KiB).
    frame = [struct.pack("<IBBQ", 0xFD2FB528, 0b11000000, 7 << 3, size)]
    for i in range(blocks):
        header = (BLOCK << 3) | (1 << 1) | (i == blocks - 1)  # a run-length block
        frame.append(header.to_bytes(3, "little") + b"\0")
    return b"".join(frame)


def _zeros_lz4(size: int) -> bytes:
    import lz4.frame

    compressor = lz4.frame.LZ4FrameCompressor()
    piece = bytes(1 << 20)
    frame = [compressor.begin(), *(compressor.compress(piece) for _ in range(size >> 20))]
    return b"".join([*frame, compressor.flush()])


def _expect(done: subprocess.CompletedProcess[str], *lines: str) -> None:
    assert (done.returncode, done.stderr.splitlines()) == (1, list(lines))


@pytest.mark.parametrize(
    ("compression", "bomb"),
    [("zstd", lambda: _zeros_zstd(2 << 30)), ("lz4", lambda: _zeros_lz4(1 << 30))],
)
def test_a_decompression_bomb_stops_at_the_size_it_declares(
    tmp_path: Path, compression: str, bomb: object
) -> None:
    path = tmp_path / "bomb.mcap"
    at = _file(path, _chunk(compression, bomb(), 100))  # type: ignore[operator]
    done = _replay(str(path))
    problem = f"the chunk at byte {at} inflates past the 100 bytes it declares"
    _expect(done, f"pyrobots-aio: error: {path}:1: {problem} (a decompression bomb?)" + COVERS)


def test_a_chunk_declaring_far_more_than_its_file_could_hold_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "bomb.mcap"
    chunk = _chunk("zstd", _zeros_zstd(200 << 20), 200 << 20)  # 6 KiB, honest about its size
    at = _file(path, chunk)
    done = _replay(str(path))
    problem = (
        f"the chunk at byte {at} would inflate the file's chunks to {200 << 20} bytes, more "
        f"than 50 times the {at + len(chunk)} bytes of file they come from "
        "(a decompression bomb?)"
    )
    _expect(done, f"pyrobots-aio: error: {path}:1: {problem}" + COVERS)


def test_a_chunk_larger_than_the_limit_is_refused_before_decompressing(tmp_path: Path) -> None:
    path = tmp_path / "big.mcap"
    at = _file(path, _chunk("zstd", _zeros_zstd(BLOCK), 1 << 40))
    done = _replay(str(path))
    problem = f"the chunk at byte {at} declares {1 << 40} bytes (the most read: {256 << 20})"
    _expect(done, f"pyrobots-aio: error: {path}:1: {problem}" + COVERS)


def test_an_endless_device_is_refused() -> None:
    done = _replay("/dev/zero")
    message = "/dev/zero: not a regular file but a character device: a recording is a file"
    _expect(done, f"pyrobots-aio: error: {message}")


def test_a_fifo_is_refused_without_waiting_for_a_writer(tmp_path: Path) -> None:
    fifo = tmp_path / "run.jsonl"
    os.mkfifo(fifo)
    done = _replay(str(fifo))
    message = f"{fifo}: not a regular file but a FIFO (named pipe): a recording is a file"
    _expect(done, f"pyrobots-aio: error: {message}")


def test_a_line_longer_than_the_limit_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "zeros.jsonl"
    with path.open("wb") as file:
        file.truncate(1 << 30)  # 1 GiB of zeros, no newline (sparse: no disk used)
    done = _replay(str(path))
    problem = "a line longer than 67108864 bytes (the most read): not a recording?"
    _expect(done, f"pyrobots-aio: error: {path}:1: {problem}")


def test_lone_surrogates_are_printed_escaped(tmp_path: Path) -> None:
    path = tmp_path / "run.jsonl"
    failed = {"outcome": "failed", "error": "E('\ud800')"}
    lines = [
        {**HEADER, "robot": "\ud800"},
        {"t": 0.0, "action": 1, "kind": "action.spawned", "name": "go\udfff", "data": {}},
        {"t": 1.0, "action": 1, "kind": "action.finished", "name": "go\udfff", "data": failed},
        {"end": 1.0, "events": 2},
    ]
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    page = tmp_path / "run.html"
    done = _replay(str(path), "--timeline", str(page))
    assert (done.returncode, done.stderr) == (0, "")
    assert done.stdout.startswith("\\ud800: 1.000 s recorded, 2 events, closed cleanly\n")
    assert "1.000 s  go\\udfff#1: E('\\ud800')" in done.stdout
    assert "go\\udfff#1" in page.read_text(encoding="utf-8")
