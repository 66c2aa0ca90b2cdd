"""The command line's progress bar (tqdm): the library reports progress
through callbacks (:data:`drake_social.app.Progress`, the planners'
``progress(iteration, best_cost)``), and only ``drake-social`` draws it."""

from __future__ import annotations

from typing import TextIO

__all__ = ["ProgressBar"]


class ProgressBar:
    """A one-line progress bar on a stream (tqdm), e.g. ``planning [####......] 800/2000, best 5.1  00:01``.

    Called as ``bar(iteration, best_cost)`` (the planners' progress callback)
    or :meth:`update` with any status text; tqdm redraws at most every
    ``interval`` seconds (and at the end), so the callback stays cheap.
    :meth:`close` ends the line.

    Args:
        total: the last step, e.g. K iterations.
        stream: where to draw (standard error).
        label: text before the bar.
        width: characters of the bar.
        interval: least time between redraws, seconds.
    """

    def __init__(self, total: int, stream: TextIO, label: str = "planning", width: int = 30,
                 interval: float = 0.1):
        from tqdm import tqdm

        self._stream = _LineEnd(stream)
        try:  # tqdm draws the bar while it is made: a Ctrl-C then must not strand the line
            self._bar = tqdm(total=max(1, int(total)), file=self._stream, desc=label, ascii=".#",
                             mininterval=interval,
                             bar_format="{desc} [{bar:%d}] {n_fmt}/{total_fmt}{postfix}  {elapsed}" % width,
                             dynamic_ncols=False, leave=True)
        except BaseException:
            if self._stream.open:
                self._stream.write("\n")
            raise

    @property
    def total(self) -> int:
        return self._bar.total

    @total.setter
    def total(self, value: int) -> None:
        self._bar.total = max(1, int(value))

    def __call__(self, iteration: int, best_cost: float) -> None:
        self.update(iteration, f"best {best_cost:.4g}" if best_cost < float("inf") else "no path yet")

    def update(self, done: int, status: str) -> None:
        """Moves the bar to ``done`` of :attr:`total` steps with ``status`` after it."""
        self._bar.set_postfix_str(status, refresh=False)
        self._bar.update(int(done) - self._bar.n)

    def step(self, done: int, total: int, status: str) -> None:
        """Moves the bar to ``done`` of ``total`` steps (a :data:`drake_social.app.Progress` callback)."""
        self.total = total
        self.update(done, status)

    def close(self) -> None:
        """Ends the bar's line, also when a Ctrl-C cut its last redraw short
        (tqdm then skips the final line)."""
        self._bar.close()
        if self._stream.open:
            self._stream.write("\n")


class _LineEnd:
    """A text stream that remembers whether its last line is still open."""

    def __init__(self, stream: TextIO):
        self._stream = stream
        self.open = False

    def write(self, text: str) -> int:
        if text:
            self.open = not text.endswith("\n")
        return self._stream.write(text)

    def flush(self) -> None:
        self._stream.flush()

    def __getattr__(self, name):  # isatty, encoding, ... of the wrapped stream
        return getattr(self._stream, name)


class BarProgress:
    """A :data:`drake_social.app.Progress` callback that draws a
    :class:`ProgressBar`, made at the first call (when the total is known).

    Args:
        stream: where to draw (standard error).
        label: text before the bar.
        interval: least time between redraws, seconds.
    """

    def __init__(self, stream: TextIO, label: str, interval: float = 0.1):
        self._stream, self._label, self._interval = stream, label, interval
        self._bar: ProgressBar | None = None

    def __call__(self, done: int, total: int, status: str) -> None:
        if self._bar is None:
            self._bar = ProgressBar(total, self._stream, label=self._label, interval=self._interval)
        self._bar.step(done, total, status)

    def close(self) -> None:
        """Ends the bar's line (nothing when it was never drawn)."""
        if self._bar is not None:
            self._bar.close()
