"""Readers and writers of :class:`dustoptics.table.Table` in renderers' formats.

One module per format; each writes atomically (a temporary file in the target
directory, renamed into place) and refuses to replace existing files unless
asked to.
"""
