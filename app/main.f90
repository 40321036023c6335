program fekap_main
   use fekap_kinds, only: dp
   implicit none
   print '(a)', 'fekap: not yet'
end program fekap_main
