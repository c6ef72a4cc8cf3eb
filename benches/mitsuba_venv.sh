# Sourced by the benchmark scripts that use Mitsuba's own Embree: sets
# `mitsuba` to the Mitsuba package in target/mitsuba-venv (made by
# `python3 benches/mitsuba_cornell.py`), or stops with what to run.
mitsuba=$(compgen -G "target/mitsuba-venv/lib/python3*/site-packages/mitsuba" | head -n1 || true)
if [ -z "$mitsuba" ] || [ ! -e "$mitsuba/libembree3.so" ]; then
  echo "no Mitsuba with Embree: run python3 benches/mitsuba_cornell.py once to make target/mitsuba-venv" >&2
  exit 1
fi
