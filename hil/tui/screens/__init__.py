"""The app's screens: Station, Plan, Run, Results, History, and the help and question dialogs."""
