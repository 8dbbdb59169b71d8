"""A window showing a help page (the user guide or the shortcut sheet) in a QTextBrowser, offline."""
from __future__ import annotations

from PySide6 import QtWidgets

__all__ = ["HelpBrowser"]


class HelpBrowser(QtWidgets.QDialog):
    """Non-modal dialog with one read-only page; links never open a network resource."""

    def __init__(self, title: str, page_html: str, parent=None):
        super().__init__(parent)
        self.setWindowTitle(title)
        self.browser = QtWidgets.QTextBrowser(self)
        self.browser.setOpenExternalLinks(False)
        self.browser.setOpenLinks(False)
        self.browser.setHtml(page_html)
        close = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Close)
        close.rejected.connect(self.close)
        lay = QtWidgets.QVBoxLayout(self)
        lay.addWidget(self.browser)
        lay.addWidget(close)
        self.resize(640, 720)

    def set_page(self, page_html: str) -> None:
        self.browser.setHtml(page_html)
