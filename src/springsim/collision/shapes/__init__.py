"""What touches in body-body contact: the bodies' surface keys (settings.py) and the surface
shapes gathered from them when the model is built (surfaces.py).
"""
