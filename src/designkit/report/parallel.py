"""Independent report tasks (the figures) shared with a forked child process, on a second core
(:func:`designkit.processes.run_tasks`).

Drawing a report's figures with matplotlib is most of the time the report takes (0.1-0.25 s a
figure on a 2-core machine), and the figures are independent of one another.  With ``processes=2``
:func:`run_tasks` forks once: the child inherits the finished run (nothing is pickled on the way
in), draws the second half of the tasks and sends their results (SVG text and captions) back
through a pipe, while the parent draws the first half.

Safety rules, each a reason to run every task in this process instead:

- ``os.fork`` is missing (not POSIX) or fewer than two cores are available;
- this process runs other Python threads (a thread holding a lock at the fork would leave the
  child deadlocked), e.g. inside a Jupyter kernel -- so the command line asks for two processes,
  the Python API's default is one;
- the child fails in any way (it dies, sends nothing, or a task raises there): the parent then
  runs the tasks it did not get, so an exception is raised here exactly as without the child.

The child leaves with :func:`os._exit` right after sending: no ``atexit`` handler, no flush of
buffers it inherited.  The results are the same bytes as a serial run (the tests compare them):
each figure's SVG depends only on its own drawing (ids are salted deterministically).
"""

from __future__ import annotations

from designkit.processes import available_cores, run_tasks

__all__ = ["available_cores", "run_tasks"]
