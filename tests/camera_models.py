"""One camera of each COLMAP model with realistic, clearly distorting parameters (COLMAP's parameter
order), shared by the camera-model tests."""

PARAMS = {
    "SIMPLE_PINHOLE": [800.0, 320.0, 240.0],
    "PINHOLE": [800.0, 790.0, 320.0, 240.0],
    "SIMPLE_RADIAL": [800.0, 320.0, 240.0, -0.1],
    "RADIAL": [800.0, 320.0, 240.0, -0.1, 0.02],
    "OPENCV": [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4],
    "OPENCV_FISHEYE": [400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4],
    "FULL_OPENCV": [800.0, 790.0, 320.0, 240.0, -0.2, 0.05, 1e-3, -5e-4, 0.01, 0.02, -0.01, 0.005],
    # omega = 0.9: 33 % barrel at 60° off axis.
    "FOV": [400.0, 395.0, 320.0, 240.0, 0.9],
    # The fisheyes' polynomials change theta_d by 5-10 % at 80°; tangential and thin-prism terms ~1 px.
    "SIMPLE_RADIAL_FISHEYE": [400.0, 320.0, 240.0, 0.05],
    "RADIAL_FISHEYE": [400.0, 320.0, 240.0, 0.05, -0.01],
    "THIN_PRISM_FISHEYE": [400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 1e-3, -5e-4, 0.002, -3e-4, 2e-3, -1e-3],
    "RAD_TAN_THIN_PRISM_FISHEYE": [400.0, 395.0, 320.0, 240.0, 0.05, -0.01, 0.002, -3e-4, 1e-5, -1e-6,
                                   1e-3, -5e-4, 2e-3, -1e-3, 3e-4, -2e-4],
    # k = -0.2: 9 % barrel at the image corner (r = 0.5).
    "SIMPLE_DIVISION": [800.0, 320.0, 240.0, -0.2],
    "DIVISION": [800.0, 790.0, 320.0, 240.0, -0.2],
    "SIMPLE_FISHEYE": [400.0, 320.0, 240.0],
    "FISHEYE": [400.0, 395.0, 320.0, 240.0],
    "EUCM": [400.0, 395.0, 320.0, 240.0, 0.6, 1.1],
}
