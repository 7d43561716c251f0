#!/usr/bin/env bash
# The FreeCAD workbench's tests in real FreeCAD 0.20 (Debian's freecad-python3, installed by
# scripts/setup.sh): the console API with `freecadcmd -t test_console`, then, when
# tests/freecad_plugin/test_gui.py exists, the GUI offscreen with `freecad -t test_gui`.
#
# The workbench is installed (linked) into the Mod folder of a throw-away HOME, so FreeCAD
# loads it as a user would and nothing of the user's own FreeCAD settings or add-ons takes
# part; the tests start the daemon ($TESSD_BIN, the release build) on a private socket.
# FreeCAD's exit status does say whether its unittest run failed; this script also reads the
# run's summary, and fails unless it ran tests, all passed and none was skipped.
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$PWD

export TESSD_BIN="${TESSD_BIN:-$REPO/target/release/tessd}"
export TESSD_SHARED_DATA="${TESSD_SHARED_DATA:-$REPO/../shared/data}"
[ -x "$TESSD_BIN" ] || { echo "run.sh: no tessd binary at $TESSD_BIN (cargo build --release -p tessd)" >&2; exit 1; }
command -v freecadcmd >/dev/null || { echo "run.sh: freecadcmd not found (scripts/setup.sh installs freecad-python3)" >&2; exit 1; }

WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessd-freecad-XXXXXX")
trap 'rm -rf "$WORK"' EXIT
export HOME="$WORK/home"
mkdir -p "$HOME"
unset XDG_DATA_HOME XDG_CONFIG_HOME FREECAD_USER_HOME
python3 freecad_plugin/install.py --link --mod-dir "$HOME/.local/share/FreeCAD/Mod"
export PYTHONPATH="$REPO/tests/freecad_plugin:$REPO/tests${PYTHONPATH:+:$PYTHONPATH}"

# run_fc LABEL LOG COMMAND...: runs a FreeCAD test command, shows its output, checks the result.
run_fc() {
  local label=$1 log=$2 status=0
  shift 2
  echo "-- $label: $*"
  local start=$SECONDS
  "$@" >"$log" 2>&1 || status=$?
  # FreeCAD's console progress bars ("Recompute... (10 %)") are noise in a log.
  sed -e 's/\t*([0-9]* %)\t*//g' -e 's/Recompute\.*//g' -e 's/\r//g' -e 's/^\t*//' "$log" | grep -v '^\s*$' | grep -v '^\s*#' || true
  local summary
  summary=$(grep -E '^(OK|FAILED)( \(.*\))?$' "$log" | tail -1 || true)
  local ran
  ran=$(grep -oE '^Ran [0-9]+ tests?' "$log" | tail -1 | grep -oE '[0-9]+' || echo 0)
  echo "-- $label: status $status, $ran tests, ${summary:-no summary}, $((SECONDS - start)) s"
  if [ "$status" -ne 0 ] || [ "$summary" != "OK" ] || [ "$ran" -eq 0 ]; then
    echo "run.sh: $label failed" >&2
    return 1
  fi
}

run_fc "console (freecadcmd)" "$WORK/console.log" freecadcmd -t test_console
if [ -f tests/freecad_plugin/test_gui.py ]; then
  # The real GUI, offscreen (test_gui.py says what it checks). FreeCAD starts on its Start
  # page, whose QtWebEngine aborts offscreen: start on the Part workbench instead.
  freecadcmd -c "import FreeCAD; FreeCAD.ParamGet('User parameter:BaseApp/Preferences/General').SetString('AutoloadModule', 'PartWorkbench'); FreeCAD.saveParameter()" >/dev/null
  # The GUI's Python does not take PYTHONPATH: -P puts the test folders on its path.
  run_fc "GUI (freecad, offscreen)" "$WORK/gui.log" env QT_QPA_PLATFORM=offscreen \
    freecad -P "$REPO/tests/freecad_plugin" -P "$REPO/tests" -t test_gui
fi
