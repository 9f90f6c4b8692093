"""twist-mocap's tracker: twist / product-of-exponentials tracking of a kinematic chain.

Pure numpy, scipy and OpenCV; never imports bpy. Run ``python -m core --help``.
"""
