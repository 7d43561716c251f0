"""tests/freecad_plugin runs inside FreeCAD, not under pytest: `bash tests/freecad_plugin/run.sh`
(`freecadcmd -t test_console`, then `freecad -t test_gui` offscreen), which scripts/test.sh
calls. pytest (`pytest tests`) leaves these modules alone: they import FreeCAD's modules, which
exist only in FreeCAD's own Python."""

collect_ignore_glob = ["test_*.py"]
