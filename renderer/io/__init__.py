"""Files in and out: images, checkpoints, scene fingerprints, denoising and error metrics."""
