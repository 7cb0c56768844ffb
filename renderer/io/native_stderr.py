"""Native libraries (Warp's, libpng inside OpenImageIO) print to file descriptor 2 on their own:
a line such as ``libpng error: IEND: out of place`` beside our one-line error. This captures
what they write and passes on only the lines worth showing."""
from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from typing import Callable, Iterator


@contextlib.contextmanager
def native_stderr(keep: Callable[[str], bool]) -> Iterator[None]:
    """Run the body with fd 2 pointing at a temporary file; afterwards write the captured lines
    that ``keep`` accepts to stderr. Python's own writes keep reaching the real stderr throughout:
    a signal handler that runs inside the body (the render command's, which prints and leaves
    through ``os._exit``) must not have its message swallowed by the capture file."""
    sys.stderr.flush()
    saved = os.dup(2)
    python_stderr = sys.stderr
    try:
        python_on_fd2 = python_stderr.fileno() == 2
    except (AttributeError, OSError, ValueError):   # pytest's capsys and the like: not fd 2
        python_on_fd2 = False
    try:
        with tempfile.TemporaryFile() as captured, \
                open(saved, "w", buffering=1, encoding=getattr(python_stderr, "encoding", None) or "utf-8",
                     errors="backslashreplace", closefd=False) as real_stderr:
            # sys.stderr is moved before fd 2 and restored after it, so at every instant a Python
            # write lands on the real stderr
            if python_on_fd2:
                sys.stderr = real_stderr
            os.dup2(captured.fileno(), 2)
            try:
                yield
            finally:
                os.dup2(saved, 2)
                sys.stderr = python_stderr
                captured.seek(0)
                for line in captured.read().decode(errors="replace").splitlines(keepends=True):
                    if keep(line):
                        sys.stderr.write(line)
    finally:
        os.close(saved)
