"""Files in and out: measured data, structure files, output sets."""
