"""splatedit.io"""
