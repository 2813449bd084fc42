from setuptools import find_packages, setup

package_name = 'hrc_joystick_node'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'bench']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/params',
         ['../../params/human.yaml', '../../params/sim_human.yaml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='The human side of hrc: Linux joystick device, sensor_msgs/Joy, simulated human.',
    license='Apache-2.0',
    entry_points={'console_scripts': [
        'human_node = hrc_joystick_node.human_node:main',
    ]},
)
