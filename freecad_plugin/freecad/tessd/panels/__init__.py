"""The task panels of the workbench's commands, one file each; what they share is in
``common.py``."""
