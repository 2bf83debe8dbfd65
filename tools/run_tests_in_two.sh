#!/usr/bin/env bash
# `make test`: the tests that start ROS processes and those that only compute run as two
# pytest processes side by side, each in a ROS domain of its own (tests/conftest.py). The
# computing side runs at a lower priority, so the ROS side, whose tests wait on processes and
# timers most of the time, sees it as a user's busy core at most. Either side collecting
# nothing is fine (a selection of one folder); both collecting nothing fails, as in
# tools/run_pytest.sh.
set -u
python=$1; shift
log=$(mktemp -t hems-computing-tests.XXXXXX)
trap 'rm -f "$log"' EXIT
echo "the tests that only compute run beside these; their report follows at the end"
HEMS_TEST_PART=computing nice -n 10 "$python" -m pytest "$@" >"$log" 2>&1 &
computing=$!
HEMS_TEST_PART=ros "$python" -m pytest "$@"
ros_rc=$?
wait "$computing"
computing_rc=$?
echo
echo "==== the tests that only compute (run beside the ones above) ===="
cat "$log"
echo "ROS side: exit code $ros_rc; computing side: exit code $computing_rc"
if [ $ros_rc -eq 5 ] && [ $computing_rc -eq 5 ]; then
  echo "pytest collected no tests: treating as failure" >&2
  exit 1
fi
for rc in $ros_rc $computing_rc; do
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 5 ]; then exit "$rc"; fi
done
exit 0
