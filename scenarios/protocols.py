"""The test protocols scenario files may name (``protocol:``): name -> what it is.

A family that follows a protocol names the one whose parameters it copies, with its
version, so that a reader can check the numbers against the public document.
"""

from __future__ import annotations

PROTOCOLS: dict[str, str] = {
    "euro-ncap-aeb-c2c-4.3.1": "Euro NCAP Test Protocol, AEB Car-to-Car systems, version 4.3.1 (2023)",
    "euro-ncap-aeb-vru-4.5.1": "Euro NCAP Test Protocol, AEB/LSS VRU systems, version 4.5.1 (2024)",
    "bittc-benign": "no protocol: a benign counterpart of a protocol case (no warning or brake expected)",
}
