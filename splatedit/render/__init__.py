"""splatedit.render"""
