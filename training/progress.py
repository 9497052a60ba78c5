"""A progress bar with ETA on stderr: redrawn in place on a terminal, one line every 30 s in a log."""

import sys
import time


def hms(seconds):
    s = int(max(0, seconds) + 0.5)
    d, s = divmod(s, 86400)
    text = f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"
    return f"{d}d {text}" if d else text


class Progress:
    def __init__(self, total, start, stream=sys.stderr, width=24, label="", unit="step"):
        self.total, self.start = total, start
        self.label, self.unit = label, unit
        self.stream = stream
        self.tty = stream.isatty()
        self.width = width
        self.t0 = time.monotonic()
        self.last = 0.0
        self.avg = {}

    def update(self, step, losses, force=False):
        """step: steps done so far; losses: dict of the last step's values (smoothed for display)."""
        for k, v in losses.items():
            self.avg[k] = v if k not in self.avg else 0.9 * self.avg[k] + 0.1 * v
        now = time.monotonic()
        if not force and now - self.last < (0.25 if self.tty else 30.0) and step < self.total:
            return
        self.last = now
        done = step - self.start
        per = (now - self.t0) / done if done else 0.0
        eta = per * (self.total - step)
        filled = self.width * step // max(1, self.total)
        bar = "#" * filled + "." * (self.width - filled)
        loss_text = "  ".join(f"{k} {self.avg[k]:.4g}" for k in ("G_GAN", "G_L1", "D_real", "D_fake")
                              if k in self.avg)
        line = (f"{self.label + ' ' if self.label else ''}[{bar}] {step}/{self.total}  "
                f"{loss_text + '  ' if loss_text else ''}{per:.3f} s/{self.unit}  ETA {hms(eta)}  "
                f"elapsed {hms(now - self.t0)}")
        if self.tty:
            self.stream.write("\r" + line + "\x1b[K" + ("\n" if step >= self.total else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def close(self):
        if self.tty:
            self.stream.write("\n")
            self.stream.flush()
