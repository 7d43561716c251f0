"""Edit ▸ Preferences ▸ tessd: the daemon's binary and socket (``daemon_link`` reads them from
``User parameter:BaseApp/Preferences/Mod/tessd`` at every connection, so a change applies to
the next command)."""

import FreeCAD

from .qt import QtCore, QtWidgets


class PreferencePage:
    """FreeCAD's Python preference page protocol: ``form``, ``loadSettings``,
    ``saveSettings`` (FreeCAD builds it with no arguments)."""

    PARAM_PATH = "User parameter:BaseApp/Preferences/Mod/tessd"

    def __init__(self, parent=None):
        self.form = QtWidgets.QWidget(parent)
        self.form.setObjectName("tessdPreferences")
        self.form.setWindowTitle("tessd")
        outer = QtWidgets.QVBoxLayout(self.form)
        box = QtWidgets.QGroupBox("Daemon")
        layout = QtWidgets.QFormLayout(box)

        self.binary = QtWidgets.QLineEdit()
        self.binary.setObjectName("BinaryPath")
        self.binary.setPlaceholderText("empty: $TESSD_BIN, else the tessd wheel's, else tessd on PATH")
        browse = QtWidgets.QToolButton()
        browse.setText("...")
        browse.clicked.connect(self._browse)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.binary, 1)
        row.addWidget(browse)
        layout.addRow("tessd program:", row)

        self.socket = QtWidgets.QLineEdit()
        self.socket.setObjectName("Socket")
        self.socket.setPlaceholderText("empty: the per-user default socket")
        layout.addRow("Socket:", self.socket)

        self.stop_on_exit = QtWidgets.QCheckBox(
            "Stop a daemon FreeCAD started when FreeCAD exits (never one another program "
            "holds)")
        self.stop_on_exit.setObjectName("StopOnExit")
        layout.addRow(self.stop_on_exit)

        self.found = QtWidgets.QLabel()
        self.found.setWordWrap(True)
        self.found.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        layout.addRow("Uses:", self.found)
        self.binary.editingFinished.connect(self._show_found)
        self.socket.editingFinished.connect(self._show_found)
        outer.addWidget(box)
        outer.addStretch(1)

    def _params(self):
        return FreeCAD.ParamGet(self.PARAM_PATH)

    def _browse(self):
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self.form, "The tessd program",
                                                        self.binary.text())
        if path:
            self.binary.setText(path)
            self._show_found()

    def _show_found(self):
        """The binary and socket the current fields lead to (the client's own lookup)."""
        try:
            import tessd
            from tessd.daemon import find_binary
            try:
                binary = find_binary(self.binary.text().strip() or None)
            except tessd.DaemonStartError as e:
                binary = "no tessd program: %s" % e
            sock = tessd.resolve_socket(self.socket.text().strip() or None)
            self.found.setText("%s\non %s" % (binary, sock))
        except Exception as e:  # the client is missing: say so here too
            self.found.setText(str(e))

    def loadSettings(self):
        p = self._params()
        self.binary.setText(p.GetString("BinaryPath", ""))
        self.socket.setText(p.GetString("Socket", ""))
        self.stop_on_exit.setChecked(p.GetBool("StopOnExit", True))
        self._show_found()

    def saveSettings(self):
        p = self._params()
        p.SetString("BinaryPath", self.binary.text().strip())
        p.SetString("Socket", self.socket.text().strip())
        p.SetBool("StopOnExit", self.stop_on_exit.isChecked())
