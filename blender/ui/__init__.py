"""The add-on's user interface: the sidebar panels and the menus."""

from . import menus, panels

classes = (*menus.classes, *panels.classes)
