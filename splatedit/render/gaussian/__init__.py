"""The 3D Gaussian Splatting renderer: resources, passes, compute tiles, GPU sort, progressive frames, numpy reference."""
