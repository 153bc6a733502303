"""TUM RGB-D list files (rgb.txt, depth.txt, mask.txt): the one reader the scripts share."""
import os


def read_list(seq, name):
    """[(timestamp, file name as written, relative to seq)] of SEQ/NAME in file order; '#' lines
    and blank lines skipped, ',' counts as a space."""
    out = []
    with open(os.path.join(seq, name)) as f:
        for line in f:
            parts = line.replace(",", " ").split()
            if parts and not parts[0].startswith("#"):
                out.append((float(parts[0]), parts[1]))
    return out
