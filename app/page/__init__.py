"""The page around the views: its layout state kept in the link (:mod:`~app.page.layout`),
its chrome (report downloads, help, notices: :mod:`~app.page.chrome`), the live plots'
title blocks and styles (:mod:`~app.page.titles`, :mod:`~app.page.bokeh`). The reports
themselves are built by :mod:`app.report`.
"""
