!> The slidelines in mesh terms (fekap_assembly_mesh builds them with the
!> mesh): each slave point with its chain of master segments, oriented along
!> the chain, or its fixed guide, and the default penalties of its gap
!> spring and rotational tie, scaled from the stiffness of the elements
!> coupled (fekap_contact_slideline's default_penalty).
module fekap_assembly_slides
   use fekap_kinds, only: dp
   use fekap_model, only: model_type, joint_prismatic
   use fekap_element_beam, only: beam_type
   use fekap_contact_slideline, only: default_penalty
   implicit none
   private

   public :: slide_type, new_slides

   !> A slideline in mesh terms: the slave point and the chain of master
   !> segments (pairs of points, in order along the line), or a fixed guide.
   type :: slide_type
      integer :: slave = 0
      !> joint_pin_in_slot or joint_prismatic.
      integer :: kind = 0
      !> Prismatic joints: the slave link's rotation dof at the slave point.
      integer :: slave_rot = 0
      logical :: ground = .false.
      real(dp) :: guide(2, 2) = 0
      !> (2, nseg): the master points of each segment along the chain.
      integer, allocatable :: seg(:, :)
      !> Penalty constants of the gap spring and of the rotational tie.
      real(dp) :: kp = 0, kr = 0
      !> Prismatic joints: initial chord angle of each segment (the tie's offset).
      real(dp), allocatable :: c0(:)
   end type slide_type

contains

   !> Slidelines in mesh terms: master chains of segments oriented along the
   !> chain, default penalties scaled from the stiffness of the elements coupled.
   !> first_interior(l): link l's first interior point; x0: the points'
   !> coordinates; elements, edof, tdof, link_rot: the mesh's elements, their
   !> dofs, the points' translation dofs and the links' end rotation dofs.
   subroutine new_slides(slides, model, first_interior, x0, elements, edof, tdof, link_rot)
      type(slide_type), allocatable, intent(out) :: slides(:)
      type(model_type), intent(in) :: model
      integer, intent(in) :: first_interior(:)
      real(dp), intent(in) :: x0(:, :)
      type(beam_type), intent(in) :: elements(:)
      integer, intent(in) :: edof(:, :), tdof(:, :), link_rot(:, :)
      integer :: i, j, k, l, m, nseg, last, e
      integer, allocatable :: pts(:)
      real(dp) :: ea_m, l_m, ei_m, ea_s, l_s, ei_s, d(2)
      if (.not. allocated(model%slidelines)) then
         allocate (slides(0))
         return
      end if
      allocate (slides(size(model%slidelines)))
      do i = 1, size(model%slidelines)
         associate (ms => model%slidelines(i), sl => slides(i))
            sl%slave = ms%slave
            sl%kind = ms%kind
            sl%ground = ms%ground
            sl%guide = ms%guide
            ea_m = 0
            ei_m = 0
            l_m = 0
            if (ms%ground) then
               allocate (sl%seg(2, 1), source=0)
               nseg = 1
               d = ms%guide(:, 2) - ms%guide(:, 1)
               sl%c0 = [atan2(d(2), d(1))]
            else
               nseg = sum(model%links(ms%master_links)%nelem)
               allocate (sl%seg(2, nseg), sl%c0(nseg))
               k = 0
               last = 0
               do j = 1, size(ms%master_links)
                  l = ms%master_links(j)
                  m = model%links(l)%nelem
                  pts = [model%links(l)%node(1), (first_interior(l) + e - 1, e=1, m - 1), model%links(l)%node(2)]
                  ! Continue the chain from where the last link ended; the
                  ! first link from its end away from the second.
                  if (last /= 0 .and. pts(m + 1) == last) pts = pts(m + 1:1:-1)
                  if (last == 0 .and. size(ms%master_links) > 1) then
                     if (any(model%links(ms%master_links(2))%node == pts(1))) pts = pts(m + 1:1:-1)
                  end if
                  do e = 1, m
                     k = k + 1
                     sl%seg(:, k) = pts(e:e + 1)
                     d = x0(:, pts(e + 1)) - x0(:, pts(e))
                     sl%c0(k) = atan2(d(2), d(1))
                  end do
                  last = pts(m + 1)
                  associate (sec => model%sections(model%links(l)%section))
                     l_m = norm2(d)
                     ea_m = max(ea_m, sec%ea)
                     ei_m = max(ei_m, sec%ei)
                  end associate
               end do
            end if
            ! The slave's own elements: the stiffest one touching the slave point.
            ea_s = 0
            ei_s = 0
            l_s = 0
            do e = 1, size(elements)
               if (any(edof(1:2, e) == tdof(1, sl%slave)) .or. &
                  & any(edof(4:5, e) == tdof(1, sl%slave))) then
                  if (elements(e)%ea/elements(e)%length > ea_s/max(l_s, tiny(1.0_dp))) then
                     ea_s = elements(e)%ea
                     ei_s = elements(e)%ei
                     l_s = elements(e)%length
                  end if
               end if
            end do
            sl%kp = default_penalty(ea_m, ea_s, l_m, l_s)
            sl%kr = default_penalty(ei_m, ei_s, l_m, l_s)
            if (ms%penalty > 0) sl%kp = ms%penalty
            if (ms%kind == joint_prismatic) then
               sl%slave_rot = link_rot(merge(1, 2, model%links(ms%slave_link)%node(1) == ms%slave), ms%slave_link)
            end if
         end associate
      end do
   end subroutine new_slides

end module fekap_assembly_slides
