"""Pictures and pages: the palette, the camera, off-screen renders, the HTML viewer, the
files of one segmentation."""
