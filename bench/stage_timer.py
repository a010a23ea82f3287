"""`python bench/stage_timer.py LOG COMMAND ARGS...`: run `python -m pipeline COMMAND ARGS...`, append
"COMMAND seconds" to LOG, exit with its code. `make bench` passes it as Make's RUN, so the stages of
one `make all` are timed one by one and their sum compares with the whole run."""
import subprocess
import sys
import time

if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = subprocess.call([sys.executable, "-m", "pipeline", *sys.argv[2:]])
    with open(sys.argv[1], "a") as fh:
        fh.write(f"{sys.argv[2]} {time.perf_counter() - t0:.3f}\n")
    sys.exit(rc)
