; Inline C between {{ and }} is C.
((c_code) @injection.content
  (#set! injection.language "c")
  (#offset! @injection.content 0 2 0 -2))
