"""The Qt binding FreeCAD runs with: PySide2 (FreeCAD 0.19-0.21, Qt 5) or PySide6 (FreeCAD 1.x
built with Qt 6). FreeCAD's own ``PySide`` shim has no ``QtWidgets`` in 0.20, so the GUI
modules import Qt from here.
"""

try:
    from PySide2 import QtCore, QtGui, QtWidgets  # noqa: F401
except ImportError:  # FreeCAD built with Qt 6
    from PySide6 import QtCore, QtGui, QtWidgets  # noqa: F401
