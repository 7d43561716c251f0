"""The error every step of reaching the daemon raises (finding its binary, its socket, starting
and checking it), worded for the artist, and the place in Blender's UI its fixes point to. Its
own module so that the binary search (:mod:`binary`) and the connection (:mod:`daemon`) both
raise it from below."""

#: Where to change the binary, in the words of Blender's UI.
PREFERENCES_PLACE = "Preferences \u203a Add-ons \u203a tessd"


class DaemonError(Exception):
    """The daemon cannot be reached; the message says why and what to do, in the words of
    Blender's UI. ``offer_preferences``: the fix is in the add-on's preferences, so a UI may
    show a button to them (see :func:`daemon.offer_preferences`)."""

    def __init__(self, message, offer_preferences=False):
        super().__init__(message)
        self.offer_preferences = offer_preferences
