"""The learned prior over rooms: the panoramic VAE (and VENI), its losses, training data and training,
fitting its latent to a panorama, its evaluation, and the view encoder that starts a photo fit.
"""
