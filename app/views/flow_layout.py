"""A layout that lays widgets out in rows and wraps them to the next row when the width runs out.

The manifold view's controls (colour, phones, hemisphere, horizon, toggles, standard views)
do not fit one row of a narrow dock; in a :class:`FlowLayout` they wrap, so the view's
minimum width is that of its widest control, not of all of them side by side.
"""
from __future__ import annotations

from PySide6 import QtCore, QtWidgets

__all__ = ["FlowLayout"]


class FlowLayout(QtWidgets.QLayout):
    """Rows of widgets, left to right, wrapping at the layout's width (height for width)."""

    def __init__(self, parent=None, *, spacing: int = 4, margins=(4, 2, 4, 2), row_spacing: int | None = None):
        super().__init__(parent)
        self._items: list = []
        self.setSpacing(spacing)
        self.row_spacing = spacing if row_spacing is None else int(row_spacing)  # between rows
        self.setContentsMargins(*margins)

    def add_group(self, widgets) -> None:
        """Add ``widgets`` side by side as one item: a group that wraps as a whole, never split."""
        box = QtWidgets.QWidget()
        row = QtWidgets.QHBoxLayout(box)
        row.setContentsMargins(0, 0, 0, 0)
        row.setSpacing(4)
        for w in widgets:
            row.addWidget(w)
        self.addWidget(box)

    # QLayout's item interface
    def addItem(self, item):  # noqa: N802 (Qt)
        self._items.append(item)

    def count(self):
        return len(self._items)

    def itemAt(self, i):  # noqa: N802
        return self._items[i] if 0 <= i < len(self._items) else None

    def takeAt(self, i):  # noqa: N802
        return self._items.pop(i) if 0 <= i < len(self._items) else None

    def expandingDirections(self):  # noqa: N802
        return QtCore.Qt.Orientation(0)

    def hasHeightForWidth(self):  # noqa: N802
        return True

    def heightForWidth(self, width):  # noqa: N802
        return self._arrange(QtCore.QRect(0, 0, width, 0), move=False)

    def setGeometry(self, rect):  # noqa: N802
        super().setGeometry(rect)
        self._arrange(rect, move=True)

    def sizeHint(self):  # noqa: N802
        return self.minimumSize()

    def minimumSize(self):  # noqa: N802
        size = QtCore.QSize()
        for item in self._items:
            size = size.expandedTo(item.minimumSize())
        m = self.contentsMargins()
        return size + QtCore.QSize(m.left() + m.right(), m.top() + m.bottom())

    def _arrange(self, rect, *, move: bool) -> int:
        """Place the items in rows within ``rect`` (when ``move``); returns the height they need."""
        m = self.contentsMargins()
        area = rect.adjusted(m.left(), m.top(), -m.right(), -m.bottom())
        x, y, row_h = area.x(), area.y(), 0
        gap = self.spacing()
        for item in self._items:
            if item.isEmpty():
                continue
            hint = item.sizeHint()
            if x > area.x() and x + hint.width() > area.right() + 1:
                x, y, row_h = area.x(), y + row_h + self.row_spacing, 0
            if move:
                item.setGeometry(QtCore.QRect(QtCore.QPoint(x, y), hint))
            x += hint.width() + gap
            row_h = max(row_h, hint.height())
        return y + row_h - rect.y() + m.bottom()
