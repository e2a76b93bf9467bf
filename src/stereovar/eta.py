"""How long a run has left, from the measured durations of its jobs, and the status text
that says it.

:class:`Pace` follows a run's jobs (when each started and ended, and its rule) and estimates
the time left: each job still to run is expected to take as long as the finished jobs of its
rule took on average (the finished jobs of every rule where none of its own has finished yet),
and at least as long as a job of its rule has been running; a running job what that leaves
of it; and the run goes on doing work at the rate it has so far (the jobs' summed durations
over the time since the first started, which counts the jobs that run side by side and the
time between jobs). A run of equal jobs one at a time so gets the time per finished job times
the jobs left. Where only jobs that ran past that estimate are left, there is no estimate.

The status text (:func:`status`) is ``<stage's count> · <k> of <n> in all · about <time>
left``; :func:`in_all`, :func:`time_left_in` and :func:`stage_count` read its parts back, so
that the command showing a run's lines can say where the run stood again, its estimate
counted down, while the run is quiet (:class:`stereovar.cli.monitor.Heartbeat`), from the
lines alone. Nothing here reads a clock: every time is given.
"""

from __future__ import annotations

import re
from collections import Counter

#: What the status says once the estimate has run out and jobs still run.
PAST_ESTIMATE = "past the estimate"

_DURATION = re.compile(r"(?:(\d+) h)? ?(?:(\d+) min)? ?(?:(\d+) s)?")
_LEFT_IN = re.compile(r"about ((?:\d+ h ?)?(?:\d+ min ?)?(?:\d+ s)?) left|past the estimate")
_IN_ALL = re.compile(r"(\d+) of (\d+) in all")
#: A stage's own count, as a status begins: ``3 of 8 jobs``, ``frame 2 of 3``.
_COUNT = re.compile(r"(?:frame )?\d+ of \d+(?: [a-z]+)?")
#: What separates the parts of a status.
SEPARATOR = " · "


def format_duration(seconds: float) -> str:
    """A duration as a status says it, rounded to what an estimate can tell: 5 s steps under a
    minute, 10 s steps under 10 minutes, minutes above.

    Parameters
    ----------
    seconds : float
        A duration; below 5 s it is said as 5 s.

    Returns
    -------
    str

    Examples
    --------
    >>> format_duration(3), format_duration(42), format_duration(290), format_duration(3725)
    ('5 s', '40 s', '4 min 50 s', '1 h 2 min')
    """
    seconds = max(float(seconds), 0.0)
    if seconds < 57.5:
        return f"{max(5, 5 * round(seconds / 5))} s"
    if seconds < 595:
        minutes, rest = divmod(10 * round(seconds / 10), 60)
        return f"{minutes} min" + (f" {rest} s" if rest else "")
    hours, minutes = divmod(round(seconds / 60), 60)
    if not hours:
        return f"{minutes} min"
    return f"{hours} h" + (f" {minutes} min" if minutes else "")


def parse_duration(text: str) -> float | None:
    """The seconds of a duration :func:`format_duration` wrote; None for other text.

    Examples
    --------
    >>> parse_duration("4 min 50 s"), parse_duration("1 h"), parse_duration("soon")
    (290.0, 3600.0, None)
    """
    match = _DURATION.fullmatch(text.strip())
    if match is None or not any(match.groups()):
        return None
    hours, minutes, seconds = (int(g or 0) for g in match.groups())
    return float(3600 * hours + 60 * minutes + seconds)


def time_left_text(seconds: float | None) -> str:
    """``about <duration> left``; :data:`PAST_ESTIMATE` at or below 0; ``""`` for None (no
    estimate yet)."""
    if seconds is None:
        return ""
    return f"about {format_duration(seconds)} left" if seconds > 0 else PAST_ESTIMATE


def status(count: str, done: int, total: int, left: float | None, *more: str) -> str:
    """The status of a run inside a stage.

    Parameters
    ----------
    count : str
        The stage's own count (``"3 of 8 jobs"``), or ``""``.
    done, total : int
        Jobs finished and planned in the whole run.
    left : float or None
        The estimated seconds left (:meth:`Pace.left`); None: none yet.
    *more : str
        Further parts, said last (``"running: calibration 1 of 2 jobs"``).

    Returns
    -------
    str

    Examples
    --------
    >>> status("3 of 8 jobs", 14, 25, 130.0)
    '3 of 8 jobs · 14 of 25 in all · about 2 min 10 s left'
    >>> status("", 0, 25, None, "running: render 0 of 2 jobs")
    '0 of 25 in all · running: render 0 of 2 jobs'
    """
    parts = [count, f"{done} of {total} in all", time_left_text(left), *more]
    return SEPARATOR.join(part for part in parts if part)


def in_all(text: str) -> str:
    """The last ``<k> of <n> in all`` of ``text`` (a stage's line), else ``""``.

    Examples
    --------
    >>> in_all("render ... done (2 jobs; 6 of 23 in all; about 1 min left)")
    '6 of 23 in all'
    """
    found = _IN_ALL.findall(text)
    return f"{found[-1][0]} of {found[-1][1]} in all" if found else ""


def time_left_in(text: str) -> float | None:
    """The last estimate of the time left that ``text`` (a status, or a stage's line) says, in
    seconds: 0 for :data:`PAST_ESTIMATE`; None where it says none.

    Examples
    --------
    >>> time_left_in("render ... done (2 jobs; 6 of 23 in all; about 1 min 10 s left)")
    70.0
    >>> time_left_in("14 of 25 in all"), time_left_in("2 of 3 in all · past the estimate")
    (None, 0.0)
    """
    found = list(_LEFT_IN.finditer(text))
    if not found:
        return None
    said = found[-1].group(1)
    return 0.0 if said is None else parse_duration(said)


def stage_count(text: str) -> str:
    """The stage's own count of a status (its part before ``<k> of <n> in all``), else
    ``""``.

    Examples
    --------
    >>> stage_count("3 of 8 jobs · 14 of 25 in all · about 2 min left")
    '3 of 8 jobs'
    >>> stage_count("· mitigations started 3 of 8 jobs · 14 of 25 in all")
    '3 of 8 jobs'
    >>> stage_count("done (1 job; 6 of 23 in all)"), stage_count("14 of 25 in all")
    ('', '')
    """
    parts = text.split(SEPARATOR)
    for k, part in enumerate(parts[1:], 1):
        if _IN_ALL.fullmatch(part):
            found = _COUNT.findall(parts[k - 1])
            return found[-1] if found else ""
    return ""


class Pace:
    """The jobs of one run, when each started and ended: the time the run has left.

    Every method takes the time ``now`` (seconds on any one clock), so that the estimate is
    a function of the events and their times alone.
    """

    def __init__(self):
        self.first = None  # when the first job started
        self.running: dict = {}  # job id: (rule, when it started)
        self.durations: dict = {}  # rule: the seconds each finished job of it took

    def start(self, jobid, rule: str, now: float) -> None:
        """Job ``jobid`` of ``rule`` started at ``now``."""
        if self.first is None:
            self.first = now
        self.running[jobid] = (rule, now)

    def end(self, jobid, now: float, *, failed: bool = False) -> None:
        """Job ``jobid`` ended at ``now``; a failed job's time measures nothing."""
        rule, started = self.running.pop(jobid, (None, None))
        if rule is not None and not failed:
            self.durations.setdefault(rule, []).append(max(now - started, 0.0))

    def left(self, planned, now: float) -> float | None:
        """Seconds the run has left at ``now`` (see the module's docstring).

        Parameters
        ----------
        planned : mapping
            Rule: the jobs of it the run has planned in all (finished, running and to come).
        now : float
            The time, on the clock of the events.

        Returns
        -------
        float or None
            None until a job has finished (nothing measured yet), and where the jobs left
            have all run past their estimate.
        """
        finished = sum(len(times) for times in self.durations.values())
        if not finished or self.first is None:
            return None
        spent = sum(sum(times) for times in self.durations.values())
        busy = spent + sum(now - started for _, started in self.running.values())
        wall = now - self.first
        if busy <= 0 or wall <= 0:
            return None
        mean = spent / finished
        cost = {rule: sum(times) / len(times) for rule, times in self.durations.items()}
        for rule, started in self.running.values():  # a job of it has run this long so far
            cost[rule] = max(cost.get(rule, mean), now - started)
        running = Counter(rule for rule, _ in self.running.values())
        work = 0.0
        for rule, jobs in planned.items():
            waiting = jobs - len(self.durations.get(rule, ())) - running[rule]
            work += max(waiting, 0) * cost.get(rule, mean)
        for rule, started in self.running.values():
            work += cost[rule] - (now - started)
        if work <= 0:
            return None
        return work * wall / busy
